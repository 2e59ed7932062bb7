"""An experiment's campaigns side by side: wall time on 1 and 2 workers, and the full protocol.

The same experiment (`--scenario`, `--strategy`, `--seeds`, `--budget-s`; no controls) runs on a
fresh copy of a data root for each runner: local processes (`--workers`, default 1 and 2; 1 runs
the campaigns one after another in this process) and a Dask LocalCluster of one-thread workers
(`--dask`, default 1 and 2). Each speed-up is against the same runner on 1 worker (targets:
≥ 1.8× on 2, issue 12). Every run must leave the same records: their rounds are compared.

With `--project N`, the slice is taken to be N campaigns of the full protocol (2 scenarios ×
{uniform, avfuzzer, evoeye, no-feedback, no-density} × 20 seeds = 200 campaigns at the paper's
budget, the initial data's simulated time) and its wall time on the largest local worker count
is scaled to the whole: the slice must hold every (scenario, method) alike (e.g. 2 seeds: 20
campaigns, 1/10). Without `--root`, `--runs` uniform runs per scenario are simulated, ingested
and a G_0 trained in a temporary folder first (a small stand-in for the paper's data); with
`--paper-data`, the paper's initial data instead: its train + validation runs per scenario (S1
107 + 25, S2 177 + 45, split 0.8 : 0.2), so that a campaign's budget is the paper's.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from benchmarks.bench_campaign import copy_root, seed_root
from benchmarks.machine import describe
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import run_experiment
from evoeye.paths import DataRoot
from evoeye.results.config import PAPER_INITIAL_RUNS
from evoeye.store import SplitSpec
from evoeye.store.feedback import read_rounds

TARGET = 1.8
TRIM_KEY = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
FULL_PROTOCOL = 2 * 5 * 20  # scenarios × methods × seeds
PRELOAD = "evoeye.evolve.campaign.workers"  # what a Dask worker runs campaigns with


def timed_experiment(root: DataRoot, args: argparse.Namespace, splits: SplitSpec,
                     workers: int | None = None, dask_address: str | None = None
                     ) -> tuple[float, list]:
    """(wall s, the rounds it stored) of the experiment on `root`."""
    base = CampaignConfig(args.scenario[0], splits=splits, n_round=args.n_round)
    t0 = time.perf_counter()
    run_experiment(root, args.scenario, base, strategies=args.strategy, seeds=args.seeds,
                   budget_s=args.budget_s, controls=0, workers=workers,
                   dask_address=dask_address, progress=lambda line: None)
    wall = time.perf_counter() - t0
    rounds = [(r.campaign_id, r.round, r.monitor_version, tuple(r.scenario_ids))
              for r in read_rounds(root)]
    return wall, rounds


def on_dask(n: int, run, preload: bool = True) -> tuple[float, list]:
    """`run(address)` with a LocalCluster of n one-thread worker processes, started as
    docs/evolution.md advises: without Dask's MALLOC_TRIM_THRESHOLD_ (training ≈ 1.5× dearer
    with it) and, with `preload`, with the campaign code imported as each worker starts (as
    the local pool's forked workers inherit it), not by its first campaign."""
    import dask
    from distributed import LocalCluster

    with dask.config.set({TRIM_KEY: None}), LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
            preload=[PRELOAD] if preload else []) as cluster:
        return run(cluster.scheduler_address)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--root", type=Path, help="data root with initial runs and a G_0 each")
    ap.add_argument("--scenario", action="append")
    ap.add_argument("--strategy", action="append")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--budget-s", type=float, help="default: the initial data's (the paper's)")
    ap.add_argument("--n-round", type=int, default=20)
    ap.add_argument("--workers", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--dask", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--no-preload", action="store_true", help="Dask workers import the "
                    "campaign code on their first campaign, inside the timed experiment")
    ap.add_argument("--project", type=int, help="the slice is this many campaigns of the "
                    f"full protocol ({FULL_PROTOCOL})")
    ap.add_argument("--runs", type=int, default=40, help="initial runs without --root")
    ap.add_argument("--paper-data", action="store_true", help="without --root: the paper's "
                    "initial runs per scenario (train + val), split 0.8 : 0.2")
    ap.add_argument("--train-frac", type=float, default=0.5, help="split of the initial runs "
                    "(with --root: as they were split when its G_0 was trained)")
    ap.add_argument("--val-frac", type=float, default=0.25)
    args = ap.parse_args()
    args.scenario = args.scenario or ["highway-cut-in"]
    args.strategy = args.strategy or ["uniform", "evoeye"]
    n_campaigns = len(args.scenario) * len(args.strategy) * len(args.seeds)
    print(f"Machine: {describe()}; load average before: {os.getloadavg()[0]:.2f}")
    print(f"{n_campaigns} campaigns: {args.scenario} × {args.strategy} × seeds {args.seeds}, "
          f"budget {args.budget_s or 'the initial data'}, N_round {args.n_round}\n")
    if args.paper_data:
        args.runs, args.train_frac, args.val_frac = PAPER_INITIAL_RUNS, 0.8, 0.2
    splits = SplitSpec(seed=0, train_frac=args.train_frac, val_frac=args.val_frac)
    runs: dict[tuple[str, int], tuple[float, list]] = {}
    with tempfile.TemporaryDirectory(prefix="bench-experiment-") as tmp:
        src = (DataRoot.existing(args.root) if args.root
               else seed_root(Path(tmp) / "seed", args.scenario, args.runs, splits))
        for n in args.workers:
            root = copy_root(src, Path(tmp) / f"local-{n}")
            runs["local", n] = timed_experiment(root, args, splits, workers=n)
            print(f"local {n}: {runs['local', n][0]:.1f} s "
                  f"(load average {os.getloadavg()[0]:.2f})", flush=True)
        for n in args.dask:
            root = copy_root(src, Path(tmp) / f"dask-{n}")
            runs["dask", n] = on_dask(n, lambda address, root=root: timed_experiment(
                root, args, splits, dask_address=address), preload=not args.no_preload)
            print(f"dask {n}: {runs['dask', n][0]:.1f} s "
                  f"(load average {os.getloadavg()[0]:.2f})", flush=True)
    print("\n| runner | workers | wall s | speed-up vs 1 worker | same records |")
    print("|---|---|---|---|---|")
    first = next(iter(runs.values()))[1] if runs else None
    for (kind, n), (wall, rounds) in runs.items():
        one = runs.get((kind, 1))
        speedup = f"{one[0] / wall:.2f}×" if one else "—"
        print(f"| {kind} | {n} | {wall:.1f} | {speedup} | {rounds == first} |")
    print(f"\ntarget: ≥ {TARGET}× on 2 workers")
    if args.project and args.workers:
        n = max(args.workers)
        wall = runs["local", n][0]
        full = wall * FULL_PROTOCOL / args.project
        print(f"projection: the slice ({n_campaigns} campaigns = {args.project}/{FULL_PROTOCOL} "
              f"of the protocol) took {wall / 3600:.2f} h on {n} local workers → the full "
              f"protocol ≈ {full / 3600:.1f} h (controls and report not included)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
