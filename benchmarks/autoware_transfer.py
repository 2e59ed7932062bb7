"""Realistic-rate round trip, measured: does a monitor score imported Autoware runs as it scores
the native ones?

1. Simulate `--train-runs` highway-cut-in runs (batch `initial`) and train a FusionMonitor on
   their train / val split (`--epochs`), as `evoeye train` does.
2. Simulate `--test-runs` other runs (batch `heldout`, other seeds: the monitor never saw them)
   in a second data root, export them as Autoware bags at realistic rates (odometry 50 Hz,
   objects, predictions and planning 10 Hz, control 33 Hz) and import the bags into a third.
3. Score every window of the held-out runs, native and imported, with the same monitor, and
   compare the frame-level AUROC (labels: H = 3 s, from each warehouse's own ground truth).

    python -m benchmarks.autoware_transfer --root /tmp/aw --train-runs 160 --test-runs 80

The done-criterion: |AUROC(imported) − AUROC(native)| ≤ 0.01. The data roots are kept under
`--root` (a second run reuses the simulated runs and the trained monitor).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from sklearn.metrics import roc_auc_score

from benchmarks.machine import describe
from evoeye.batch import plan_uniform, run_batch
from evoeye.monitor.registry import list_versions, load_monitor
from evoeye.monitor.train import train_monitor
from evoeye.paths import DataRoot
from evoeye.sources.autoware.export import export_run
from evoeye.sources.autoware.importer import import_bags
from evoeye.store import ingest, load_windows
from evoeye.store.ingest import discover_logs

SCENARIO = "highway-cut-in"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", type=Path, required=True)
    ap.add_argument("--train-runs", type=int, default=160)
    ap.add_argument("--test-runs", type=int, default=80)
    ap.add_argument("--epochs", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    t0 = time.perf_counter()
    train_root = DataRoot.resolve(args.root / "train")
    native_root = DataRoot.resolve(args.root / "native")
    imported_root = DataRoot.resolve(args.root / "imported")
    run_batch(plan_uniform(SCENARIO, args.train_runs, 1, batch="initial"), train_root,
              workers=args.workers)
    ingest(train_root)
    versions = list_versions(train_root)
    version = versions[-1] if versions else train_monitor(train_root, SCENARIO,
                                                          epochs=args.epochs, seed=0)
    monitor = load_monitor(train_root, version)
    run_batch(plan_uniform(SCENARIO, args.test_runs, 2, batch="heldout"), native_root,
              workers=args.workers)
    ingest(native_root)
    bags = [export_run(log, args.root / "bags", rates="realistic")
            for log in discover_logs(native_root.runs)]
    report = import_bags(imported_root, bags)
    assert not report.failed, report.failed
    rows = []
    for name, root in (("native", native_root), ("imported", imported_root)):
        windows = load_windows(root, context_len=monitor.context_len)
        scores = monitor.score(windows)
        rows.append((name, len(windows), int(windows.label.sum()),
                     roc_auc_score(windows.label, scores)))
    print(describe())
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}; "
          f"{time.perf_counter() - t0:.0f} s; monitor {version} "
          f"(val AUROC {monitor.card['metrics']['val']['auroc']:.4f})")
    print("| held-out runs | windows | unsafe | AUROC |")
    print("|---|---|---|---|")
    for name, n, pos, auc in rows:
        print(f"| {name} | {n} | {pos} | {auc:.4f} |")
    gap = abs(rows[1][3] - rows[0][3])
    print(f"|AUROC gap| = {gap:.4f}: target ≤ 0.01 {'met' if gap <= 0.01 else 'NOT met'}")


if __name__ == "__main__":
    main()
