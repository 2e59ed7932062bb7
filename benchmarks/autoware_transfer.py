"""Realistic-rate round trip, measured: does a monitor score imported Autoware runs as it scores
the native ones?

1. Simulate `--train-runs` highway-cut-in runs (batch `initial`) and train a FusionMonitor on
   their train / val split (`--epochs`), as `evoeye train` does — unless `--root` already holds
   a trained monitor (then it is reused, and the training runs are not touched).
2. Simulate `--test-runs` other runs (batch `heldout`, other seeds: the monitor never saw them)
   in a second data root, export them as Autoware bags at realistic rates (odometry 50 Hz,
   objects, predictions and planning 10 Hz, control 33 Hz) and import the bags into a third.
3. Score the windows of the frames both warehouses have, native and imported, with the same
   monitor, and compare the frame-level AUROC (labels: H = 3 s, from each warehouse's own
   ground truth, checked equal), with a 95 % interval of the gap (paired bootstrap over the
   held-out runs, 1000 resamples). Also reported: how the two scores agree (Spearman), each
   feature's 95th percentile |imported − native| (the documented tolerances), and the AUROC of
   the imported windows with one feature group swapped back to its native values (where a gap
   comes from).

    python -m benchmarks.autoware_transfer --root /tmp/aw --train-runs 160 --test-runs 80
    python -m benchmarks.autoware_transfer --root /tmp/aw --stack apollo   # cyber records

The done-criterion: |AUROC(imported) − AUROC(native)| ≤ 0.01. The data roots are kept under
`--root` (a second run reuses the simulated runs, the bags, the imported runs and the trained
monitor: remove `bags/` and `imported/` after changing the exporter or the importer). CPU time
is the process's (`time.process_time`), the machine being shared.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import torch
from scipy.stats import bootstrap, spearmanr
from sklearn.metrics import roc_auc_score

from benchmarks.machine import describe
from evoeye.batch import plan_uniform, run_batch
from evoeye.monitor.fusion import SCORE_BATCH, FusionMonitor
from evoeye.monitor.registry import list_versions, load_monitor
from evoeye.monitor.train import train_monitor
from evoeye.paths import DataRoot
from evoeye.sources.apollo.export import export_record
from evoeye.sources.apollo.run import RECORDS
from evoeye.sources.autoware.compare import (
    FEATURE_GROUPS,
    Matched,
    feature_gaps,
    matched_windows,
)
from evoeye.sources.autoware.export import export_run
from evoeye.sources.autoware.importer import import_bags
from evoeye.store import ingest
from evoeye.store.features import PERCEPTION_FEATURES, PLAN_FEATURES
from evoeye.store.ingest import discover_logs

SCENARIO = "highway-cut-in"
NAMED = {"perception": PERCEPTION_FEATURES, "plan": PLAN_FEATURES}  # groups of named features


def _load(loadavg: tuple[float, ...]) -> str:
    return " ".join(f"{x:.2f}" for x in loadavg)


def _monitor(root: DataRoot, runs: int, epochs: int, workers: int) -> FusionMonitor:
    versions = list_versions(root)
    if not versions:
        run_batch(plan_uniform(SCENARIO, runs, 1, batch="initial"), root, workers=workers)
        ingest(root)
        versions = [train_monitor(root, SCENARIO, epochs=epochs, seed=0)]
    return load_monitor(root, versions[-1])


def _score(monitor: FusionMonitor, arrays: dict[str, np.ndarray]) -> np.ndarray:
    """(B,) risks of window arrays, SCORE_BATCH windows at a time."""
    n = len(arrays["label"])
    return np.concatenate([monitor.score_batch(
        {k: torch.from_numpy(np.ascontiguousarray(v[i:i + SCORE_BATCH]))
         for k, v in arrays.items()}) for i in range(0, n, SCORE_BATCH)])


def _gap_interval(m: Matched, s_native: np.ndarray, s_imported: np.ndarray
                  ) -> tuple[float, float]:
    """95 % interval of AUROC(imported) − AUROC(native), the held-out runs resampled."""
    runs, run_of = np.unique(m.scenario_id, return_inverse=True)
    members = [np.flatnonzero(run_of == r) for r in range(len(runs))]
    y = m.native["label"]

    def gap(picked: np.ndarray) -> float:
        rows = np.concatenate([members[r] for r in picked])
        if y[rows].min() == y[rows].max():
            return np.nan  # a resample without an unsafe (or a safe) window
        return roc_auc_score(y[rows], s_imported[rows]) - roc_auc_score(y[rows], s_native[rows])

    ci = bootstrap((np.arange(len(runs)),), gap, vectorized=False, n_resamples=1000,
                   method="percentile", rng=np.random.default_rng(0)).confidence_interval
    return ci.low, ci.high


def _gap_lines(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> list[str]:
    lines = ["| features | p95 |imported − native| |", "|---|---|"]
    for name in FEATURE_GROUPS:
        p95 = feature_gaps(a, b, name)
        names = NAMED.get(name)
        text = (", ".join(f"{n} {v:.3g}" for n, v in zip(names, p95, strict=True)) if names
                else f"max {p95.max():.3g} (first {p95[0]:.3g}, last {p95[-1]:.3g})")
        lines.append(f"| {name} | {text} |")
    return lines


def _swap_lines(monitor: FusionMonitor, a: dict[str, np.ndarray],
                b: dict[str, np.ndarray]) -> list[str]:
    """The imported windows' AUROC with one group (then one plan channel) native again."""
    y = a["label"]
    lines = ["| imported, with native … | AUROC |", "|---|---|"]
    for name in FEATURE_GROUPS:
        swapped = dict(b, **{k: a[k] for k in (name, f"{name}_mask") if k in a})
        lines.append(f"| {name} | {roc_auc_score(y, _score(monitor, swapped)):.4f} |")
    for j, channel in enumerate(PLAN_FEATURES):
        plan = b["plan"].copy()
        plan[..., j] = a["plan"][..., j]
        auc = roc_auc_score(y, _score(monitor, dict(b, plan=plan)))
        lines.append(f"| plan {channel} | {auc:.4f} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", type=Path, required=True)
    ap.add_argument("--train-runs", type=int, default=160)
    ap.add_argument("--test-runs", type=int, default=80)
    ap.add_argument("--epochs", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stack", choices=("autoware", "apollo"), default="autoware",
                    help="export and import as Autoware bags or as Apollo cyber records")
    args = ap.parse_args()
    load_before, t0, cpu0 = os.getloadavg(), time.perf_counter(), time.process_time()
    monitor = _monitor(DataRoot.resolve(args.root / "train"), args.train_runs, args.epochs,
                       args.workers)
    native_root = DataRoot.resolve(args.root / "native")
    apollo = args.stack == "apollo"
    imported_root = DataRoot.resolve(args.root / ("imported-apollo" if apollo else "imported"))
    run_batch(plan_uniform(SCENARIO, args.test_runs, 2, batch="heldout"), native_root,
              workers=args.workers)
    ingest(native_root)
    if apollo:
        records_dir = args.root / "records"
        bags = [records_dir / f"{log.stem}.record"
                if (records_dir / f"{log.stem}.record").exists()
                else export_record(log, records_dir, rates="realistic")
                for log in discover_logs(native_root.runs)]
    else:
        bags_dir = args.root / "bags"
        bags = [bags_dir / log.stem if (bags_dir / log.stem / "metadata.yaml").exists()
                else export_run(log, bags_dir, rates="realistic")
                for log in discover_logs(native_root.runs)]
    report = import_bags(imported_root, bags, recordings=RECORDS if apollo else None)
    assert not report.failed, report.failed
    ids = sorted(p.name.removesuffix(".record") for p in bags)
    m = matched_windows(native_root, imported_root, ids, monitor.context_len)
    a, b = m.native, m.imported
    assert np.array_equal(a["label"], b["label"]), "the imported labels differ"
    s_native, s_imported = _score(monitor, a), _score(monitor, b)
    auc_native, auc_imported = (roc_auc_score(a["label"], s) for s in (s_native, s_imported))
    print(describe())
    print(f"load average before {_load(load_before)}, after {_load(os.getloadavg())}; "
          f"{time.perf_counter() - t0:.0f} s wall, {time.process_time() - cpu0:.0f} s CPU; "
          f"monitor {monitor.version} (val AUROC {monitor.card['metrics']['val']['auroc']:.4f})")
    print("\n| held-out runs | windows (both) | native only | unsafe | AUROC native | "
          "AUROC imported | gap [95 % interval] |\n|---|---|---|---|---|---|---|")
    low, high = _gap_interval(m, s_native, s_imported)
    print(f"| {len(ids)} | {len(a['label'])} | {m.left_out} | {int(a['label'].sum())} | "
          f"{auc_native:.4f} | {auc_imported:.4f} | {auc_imported - auc_native:+.4f} "
          f"[{low:+.4f}, {high:+.4f}] |")
    rho = spearmanr(s_native, s_imported).statistic
    print(f"\nscores native vs imported: Spearman {rho:.4f}, "
          f"median |difference| {np.median(np.abs(s_native - s_imported)):.4f}\n")
    print("\n".join(_gap_lines(a, b)) + "\n")
    print("\n".join(_swap_lines(monitor, a, b)) + "\n")
    gap = abs(auc_imported - auc_native)
    print(f"|AUROC gap| = {gap:.4f}: target ≤ 0.01 {'met' if gap <= 0.01 else 'NOT met'}")


if __name__ == "__main__":
    main()
