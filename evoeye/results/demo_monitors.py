"""The FusionMonitors shipped for the demo: `python -m evoeye.results.demo_monitors` (`make
demo-monitors`).

Per logical scenario: simulate `--runs` uniformly sampled runs with seed `--seed` (batch
`pretrain`; the demo simulates with other seeds, so it never tests on these), ingest them, train
a FusionMonitor (L = 5, all module inputs, training seed 0) on 80 % of them, calibrate its
thresholds on the other 20 %, and copy the version into `evoeye/monitor/pretrained/` in place of
the scenario's previous one. Version ids hash the weights and what produced them, so the same
arguments give the same ids.
"""

from __future__ import annotations

import argparse
import shutil
from collections.abc import Callable
from pathlib import Path

from evoeye.batch import plan_uniform, run_batch
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.monitor.pretrained import PACKAGED, packaged_versions
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from evoeye.store import SplitSpec, ingest

RUNS = 500
SEED = 1000
BATCH = "pretrain"
SPLITS = SplitSpec(seed=0, train_frac=0.8, val_frac=0.2)  # no test split: the demo tests


def build(root: DataRoot, runs: int = RUNS, seed: int = SEED, workers: int = 2,
          out: Path = PACKAGED, say: Callable[[str], None] = print) -> dict[str, str]:
    """Simulate, ingest, train and package one monitor per logical scenario; their versions."""
    from evoeye.monitor.train import train_monitor

    for scenario in SCENARIOS:
        say(f"{scenario}: simulating {runs} runs (seed {seed})")
        run_batch(plan_uniform(scenario, runs, seed, batch=BATCH), root, workers=workers)
    say("ingesting")
    ingest(root)
    fusion, shipped = FAMILIES[DEFAULT_FAMILY], packaged_versions(out)
    versions = {}
    for scenario in SCENARIOS:
        say(f"{scenario}: training")
        version = train_monitor(root, scenario, seed=0, splits=SPLITS)
        if shipped.get(scenario) not in (None, version):
            shutil.rmtree(out / shipped[scenario])
        if not (out / version).exists():
            shutil.copytree(fusion.version_dir(root, version), out / version)
        versions[scenario] = version
        say(f"{scenario}: {version} → {out / version}")
    return versions


def main() -> None:
    ap = argparse.ArgumentParser(prog="python -m evoeye.results.demo_monitors",
                                 description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True, help="data root for the training runs")
    ap.add_argument("--runs", type=int, default=RUNS, help="runs per logical scenario")
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    build(DataRoot.resolve(args.root), args.runs, args.seed, args.workers)


if __name__ == "__main__":
    main()
