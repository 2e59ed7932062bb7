"""A FusionMonitor trained from scratch: seconds per seed, training frames per second per epoch,
where the time goes, and k seeds together against one.

On a data root holding a scenario's runs (`--root`; e.g. RQ1's S1 data, 1 058 training runs),
with the split RQ1 uses (`--train-frac`, `--val-frac`, `--test-batch`), for each recipe of
`--recipes`:

  one seed      `train_monitor` at `--seed`: wall and CPU seconds of the whole call (windows
                loaded, normalisers, training, calibration, saving), and from the card the
                epochs, the loop's wall and CPU seconds and its phases (batches, forward,
                backward, optimiser, validation); throughput = training frames × epochs ÷
                the loop's seconds (the issue's measure, wall and CPU)
  k seeds       `train_monitors` at `--seed`, `--seed` + 1, …: wall and CPU seconds, against
                k × the one seed and against the one seed

With `--aem-recipes`, the AEM baseline is fitted by each (`fit_aem`: its training windows
gathered, the autoencoder trained), wall and CPU seconds. The versions go to a scratch root
beside `--root` (its warehouse hard-linked, removed after), so the data root gets none. On a
shared machine wall time follows the load: the load average is printed before and after, and
CPU seconds (this process, all its threads, and the seeds' processes) beside wall.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

from benchmarks.machine import describe
from evoeye.baselines.families import fit_aem
from evoeye.monitor.registry import read_card
from evoeye.monitor.train import train_monitor, train_monitors
from evoeye.paths import DataRoot
from evoeye.store import RunFilter, SplitSpec


def scratch_root(src: DataRoot, folder: Path) -> DataRoot:
    """A data root in `folder` with `src`'s warehouse, its files hard-linked (copied across
    devices): trainings read it and write their versions there."""
    def link(a: str, b: str) -> None:
        try:
            os.link(a, b)
        except OSError:
            shutil.copy2(a, b)

    shutil.copytree(src.path / "warehouse", folder / "warehouse", copy_function=link)
    return DataRoot.resolve(folder)


def cpu_s() -> float:
    """CPU seconds of this process and of its children that have ended (forked seeds)."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def timed(fn):
    """(result, wall s, CPU s of this process and the children it waited for) of fn()."""
    t0, c0 = time.perf_counter(), cpu_s()
    out = fn()
    return out, time.perf_counter() - t0, cpu_s() - c0


def load() -> str:
    return " / ".join(f"{x:.1f}" for x in os.getloadavg())


def report_one(recipe: str, card: dict, wall_s: float, cpu_s: float) -> float:
    """Print one seed's figures; its call's wall seconds."""
    t, frames = card["training"], card["data"]["train"]["frames"]
    work = frames * t["epochs_run"]
    print(f"| {recipe} | {card['data']['train']['runs']} | {frames:,} | {t['epochs_run']} "
          f"({t['best_epoch']}) | {wall_s:.0f} | {cpu_s:.0f} | {t['time_s']:.0f} | "
          f"{t['cpu_s']:.0f} | {work / t['time_s']:,.0f} | {work / t['cpu_s']:,.0f} |")
    return wall_s


def report_phases(recipe: str, card: dict, wall_s: float, cpu_s: float) -> None:
    phases = card["training"]["phases"]
    loop = card["training"]["cpu_s"]
    cells = [f"{p['cpu_s']:.1f} ({100 * p['cpu_s'] / cpu_s:.0f} %)" for p in phases.values()]
    rest = cpu_s - loop
    print(f"| {recipe} | " + " | ".join(cells)
          + f" | {rest:.1f} ({100 * rest / cpu_s:.0f} %) | {cpu_s:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True, help="data root with the scenario's runs")
    ap.add_argument("--scenario", default="highway-cut-in")
    ap.add_argument("--test-batch", default="test-seed60607",
                    help="the held-out batch (RQ1's Test Set); '' for none")
    ap.add_argument("--train-frac", type=float, default=0.8)
    ap.add_argument("--val-frac", type=float, default=0.2)
    ap.add_argument("--recipes", default="v2", help="comma list, e.g. v1,v2")
    ap.add_argument("--seed", type=int, default=100, help="first seed (not one RQ1 records)")
    ap.add_argument("--k", type=int, default=3, help="seeds trained together (0: skip)")
    ap.add_argument("--aem-recipes", default="", help="also fit the AEM by these, e.g. v1,v2")
    args = ap.parse_args()
    src = DataRoot.existing(args.root)
    splits = SplitSpec(0, args.train_frac, args.val_frac, args.test_batch or None)
    runs = {split: RunFilter(logical_scenario=args.scenario, split=split, splits=splits,
                             max_round=0 if split == "train" else None)
            for split in ("train", "val")}
    kwargs = {"splits": splits, "train_runs": runs["train"], "val_runs": runs["val"]}
    print(f"Machine: {describe()}; load average {load()} at the start")
    ones: dict[str, tuple[dict, float, float]] = {}
    together: dict[str, tuple[list[dict], float, float]] = {}
    with tempfile.TemporaryDirectory(prefix=".bench-train-", dir=src.path.parent) as tmp:
        root = scratch_root(src, Path(tmp))
        for recipe in args.recipes.split(","):
            version, wall, cpu = timed(lambda recipe=recipe: train_monitor(
                root, args.scenario, seed=args.seed, recipe=recipe, **kwargs))
            ones[recipe] = (read_card(root, version), wall, cpu)
            print(f"{recipe}: one seed done (load average {load()})", flush=True)
            if args.k > 1:
                seeds = list(range(args.seed, args.seed + args.k))
                versions, wall, cpu = timed(lambda recipe=recipe, seeds=seeds: train_monitors(
                    root, args.scenario, seeds=seeds, recipe=recipe, **kwargs))
                together[recipe] = ([read_card(root, v) for v in versions], wall, cpu)
                assert versions[0] == version, "a seed trained together differs from alone"
                print(f"{recipe}: {args.k} seeds done (load average {load()})", flush=True)
        aems = {recipe: timed(lambda recipe=recipe: fit_aem(
                    root, args.scenario, splits, seed=args.seed, runs=runs["train"],
                    recipe=recipe))
                for recipe in filter(None, args.aem_recipes.split(","))}
    print(f"\nOne seed, {args.scenario} (load average {load()} at the end):\n")
    print("| recipe | train runs | train frames | epochs (best) | call wall s | call CPU s "
          "| loop wall s | loop CPU s | frames/s/epoch (wall) | frames/s/epoch (CPU) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for recipe, (card, wall, cpu) in ones.items():
        report_one(recipe, card, wall, cpu)
    print("\nWhere one seed's CPU time goes (s, share of the call):\n")
    print("| recipe | " + " | ".join(next(iter(ones.values()))[0]["training"]["phases"])
          + " | loading, normalisers, calibration, saving | call |")
    print("|---|" + "---:|" * (len(next(iter(ones.values()))[0]["training"]["phases"]) + 2))
    for recipe, (card, wall, cpu) in ones.items():
        report_phases(recipe, card, wall, cpu)
    if aems:
        print("\nThe AEM, fitted on the same training runs:\n")
        print("| recipe | epochs | batch | wall s | CPU s | v1 ÷ this (CPU) |")
        print("|---|---:|---:|---:|---:|---:|")
        for recipe, (aem, wall, cpu) in aems.items():
            ratio = aems["v1"][2] / cpu if "v1" in aems else float("nan")
            print(f"| {recipe} | {aem.config.epochs} | {aem.config.batch_size} | {wall:.0f} | "
                  f"{cpu:.0f} | {ratio:.1f} |")
    if together:
        print(f"\n{args.k} seeds together against one:\n")
        print("| recipe | wall s | CPU s | × one seed (wall) | × one seed (CPU) | epochs |")
        print("|---|---:|---:|---:|---:|---|")
        for recipe, (cards, wall, cpu) in together.items():
            _, one_wall, one_cpu = ones[recipe]
            epochs = ", ".join(str(c["training"]["epochs_run"]) for c in cards)
            print(f"| {recipe} | {wall:.0f} | {cpu:.0f} | {wall / one_wall:.2f} | "
                  f"{cpu / one_cpu:.2f} | {epochs} |")


if __name__ == "__main__":
    main()
