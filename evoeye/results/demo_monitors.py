"""The FusionMonitors shipped for the demo: `python -m evoeye.results.demo_monitors` (`make
demo-monitors`).

Per logical scenario: simulate `--runs` uniformly sampled runs with seed `--seed` (batch
`pretrain`; the demo simulates with other seeds, so it never tests on these), ingest them, train
a FusionMonitor (all module inputs, training seed 0) by `--recipe` — by default the one `evoeye
train` trains (`recipes.COMMAND_RECIPE`), as its recipe has it; the legacy recipe v1 at most
EPOCHS epochs, early-stopped after PATIENCE without a better validation loss — on 80 % of them,
calibrate its
thresholds on the other 20 %, and copy the version into `evoeye/monitor/pretrained/` in place of
the scenario's previous one, its card saying which runs trained it (`shipped`: batch,
simulation seed, runs per scenario). Version ids hash the weights and what produced them, so the
same arguments give the same ids.
"""

from __future__ import annotations

import argparse
import json
import shutil
from collections.abc import Callable, Sequence
from pathlib import Path

from evoeye.batch import plan_uniform, run_batch
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.monitor.pretrained import PACKAGED, packaged_versions
from evoeye.monitor.recipes import COMMAND_RECIPE, LEGACY_RECIPE, RECIPES
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from evoeye.store import SplitSpec, ingest

RUNS = 500
SEED = 1000
EPOCHS, PATIENCE = 20, 4  # v1: hundreds of runs: the validation loss settles within a few epochs
BATCH = "pretrain"
SPLITS = SplitSpec(seed=0, train_frac=0.8, val_frac=0.2)  # no test split: the demo tests


def stamp(version_dir: Path, runs: int, seed: int) -> None:
    """Write into a shipped version's card the runs it was trained on (not in its id)."""
    fusion = FAMILIES[DEFAULT_FAMILY]
    path = version_dir / fusion.meta_file
    card = json.loads(path.read_text())
    card["shipped"] = {"made_by": "python -m evoeye.results.demo_monitors", "batch": BATCH,
                       "simulation_seed": seed, "runs_per_scenario": runs,
                       "sampling": "uniform", "training_seed": 0}
    path.write_text(json.dumps(card, indent=2) + "\n")


def build(root: DataRoot, runs: int = RUNS, seed: int = SEED, workers: int = 2,
          out: Path = PACKAGED, say: Callable[[str], None] = print,
          scenarios: Sequence[str] = tuple(SCENARIOS), recipe: str = COMMAND_RECIPE
          ) -> dict[str, str]:
    """Simulate, ingest, train and package one monitor per logical scenario; their versions
    (runs already simulated or ingested are skipped, so an interrupted build resumes)."""
    from evoeye.monitor.train import train_monitor

    for scenario in scenarios:
        say(f"{scenario}: simulating {runs} runs (seed {seed})")
        run_batch(plan_uniform(scenario, runs, seed, batch=BATCH), root, workers=workers)
    say("ingesting")
    ingest(root)
    fusion, shipped = FAMILIES[DEFAULT_FAMILY], packaged_versions(out)
    versions = {}
    for scenario in scenarios:
        say(f"{scenario}: training")
        legacy = {"epochs": EPOCHS, "patience": PATIENCE} if recipe == LEGACY_RECIPE else {}
        version = train_monitor(
            root, scenario, seed=0, splits=SPLITS, recipe=recipe, **legacy,
            progress=lambda row: say(f"  epoch {row['epoch']}: val loss {row['val_loss']:.4f}"))
        if shipped.get(scenario) not in (None, version):
            shutil.rmtree(out / shipped[scenario])
        if not (out / version).exists():
            shutil.copytree(fusion.version_dir(root, version), out / version)
            stamp(out / version, runs, seed)
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
    ap.add_argument("--recipe", default=COMMAND_RECIPE, choices=sorted(RECIPES),
                    help="training recipe (default: what `evoeye train` trains)")
    ap.add_argument("--scenario", action="append", choices=sorted(SCENARIOS),
                    help="only this logical scenario (repeatable; default: all)")
    args = ap.parse_args()
    build(DataRoot.resolve(args.root), args.runs, args.seed, args.workers,
          scenarios=args.scenario or tuple(SCENARIOS), recipe=args.recipe)


if __name__ == "__main__":
    main()
