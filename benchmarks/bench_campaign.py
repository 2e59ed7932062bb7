"""A campaign's rounds, profiled: where the wall time goes, and its cost against simulation alone.

One campaign (`--strategy`, default evoeye; `--update`, default retrain; N_round = `--n-round`)
runs `--rounds` rounds on a private copy of a data root holding the scenario's initial runs and a
G_0 (`--root`; without it, `--runs` uniform runs are simulated, ingested and a G_0 trained in a
temporary folder first). Each round is broken into the campaign's phases
(`evoeye.evolve.campaign.phases`): simulate, score, ingest, train, refresh, assess, state. Then
the very runs the campaign acquired are simulated and logged again, alone, one after another in
this process: the campaign's cost is its wall time over that (target ≤ 1.5×, issues 12 and 41).
Round 0 (G_0 scores D_init and is assessed) is paid once per campaign and shown apart. Wall
seconds and this process's CPU seconds are both given: on a shared machine the CPU ratio is the
one that load distorts less (everything runs in this one process, torch on one thread).

With several `--update` modes and `--seeds`, one campaign runs per seed and mode (interleaved,
seed by seed), each mode's cost is summarised (total, simulation alone, the update's training,
their ratios), and each mode's last G_r is compared with the first mode's on the Test Set:
the paired difference of AUPRC (and AUROC) over the seeds, with a 95 % t interval.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import numpy as np

from benchmarks.machine import describe
from evoeye.batch import plan_uniform, run_batch, simulate_and_keep_all, simulate_and_log
from evoeye.evolve.campaign.assess import Assessor
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.phases import PHASES
from evoeye.log import read_run
from evoeye.paths import DataRoot
from evoeye.sim.runner import run_spec
from evoeye.store import SplitSpec, ingest
from evoeye.store.feedback import read_rounds

TARGET = 1.5


def seed_root(path: Path, scenarios: list[str], runs: int | Mapping[str, int],
              splits: SplitSpec) -> DataRoot:
    """A data root with `runs` uniform runs per scenario (or `runs[scenario]`), ingested, and a
    G_0 for each."""
    from evoeye.monitor import train_monitor

    root = DataRoot.resolve(path)
    for scenario in scenarios:
        n = runs if isinstance(runs, int) else runs[scenario]
        run_batch(plan_uniform(scenario, n, seed=11), root, workers=1)
    ingest(root)
    for scenario in scenarios:
        train_monitor(root, scenario, seed=0, splits=splits, epochs=5)
    return root


def copy_root(src: DataRoot, dst: Path) -> DataRoot:
    """A private copy of a data root (campaigns write into it)."""
    shutil.copytree(src.path, dst, ignore=shutil.ignore_patterns("reports", "quarantine"))
    return DataRoot.resolve(dst)


def simulate_alone(root: DataRoot, campaign_id: str, scenario: str,
                   out: DataRoot) -> tuple[float, float, int, float]:
    """(wall s, CPU s, runs) to simulate and log the campaign's acquired runs again, one by
    one, and the CPU s to do it with the lockstep engine (`simulate_and_keep_all`, one group
    per round, as the campaign groups them at most)."""
    rounds = [r.scenario_ids for r in read_rounds(root, campaign_id) if r.scenario_ids]
    specs = []
    for ids in rounds:
        specs.append([])
        for sid in ids:
            meta = read_run(root.run_log(scenario, campaign_id, sid), topics=()).metadata
            specs[-1].append(run_spec(scenario, meta["params"], int(meta["seed"]),
                                      batch="alone", source=str(meta["source"]),
                                      round=int(meta["round"])))
    t0, c0 = time.perf_counter(), time.process_time()
    for spec in (s for group in specs for s in group):
        simulate_and_log(spec, out)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    c0 = time.process_time()
    for group in specs:
        simulate_and_keep_all([replace(s, batch="together") for s in group], out)
    return wall, cpu, sum(map(len, specs)), time.process_time() - c0


def profile(root: DataRoot, cfg: CampaignConfig, rounds: int
            ) -> tuple[list[tuple[dict, dict]], tuple[dict, dict]]:
    """([(wall, CPU) phase seconds of each round], those of round 0), each with "total". The
    rounds run as `Campaign.run` runs them (a round's share of resuming counts in round 1)."""
    t0, c0 = time.perf_counter(), time.process_time()
    campaign = Campaign(root, cfg)
    campaign = Campaign(root, cfg, assess=Assessor.of(campaign))  # its set-up is round 0's
    campaign.start()
    clock = campaign.clock

    def mark() -> tuple[dict, dict]:
        return ({**clock.seconds, "total": time.perf_counter()},
                {**clock.cpu_seconds, "total": time.process_time()})

    marks = [mark()]
    first = ({**clock.seconds, "total": marks[0][0]["total"] - t0},
             {**clock.cpu_seconds, "total": marks[0][1]["total"] - c0})
    campaign.run(max_rounds=rounds, on_round=lambda row, state: marks.append(mark()))
    out = [tuple({k: b[i][k] - a[i][k] for k in a[i]} for i in (0, 1))
           for a, b in zip(marks, marks[1:], strict=False)]
    return out, first


def _pct(x: float | None) -> str:
    return "—" if x is None else f"{100 * x:.1f}"


def row(label: str, seconds: dict) -> str:
    cells = " | ".join(f"{seconds[p]:.2f}" for p in PHASES)
    other = seconds["total"] - sum(seconds[p] for p in PHASES)
    return f"| {label} | {cells} | {other:.2f} | {seconds['total']:.2f} |"


def table(kind: str, rounds: list[dict], first: dict) -> dict:
    """Print one table (wall or CPU seconds) of the rounds; the rounds' sums."""
    print(f"\n{kind} seconds\n\n| round | {' | '.join(PHASES)} | other | total |")
    print(f"|---|{'---|' * (len(PHASES) + 2)}")
    print(row("0 (G_0)", first))
    for i, seconds in enumerate(rounds, start=1):
        print(row(str(i), seconds))
    total = {k: sum(r[k] for r in rounds) for k in (*PHASES, "total")}
    print(row("rounds 1+", total))
    return total


def run_one(src: DataRoot, cfg: CampaignConfig, rounds: int, tmp: Path) -> dict:
    """One campaign on a private copy of `src`, profiled, and its runs simulated again alone."""
    root = copy_root(src, tmp / "data")
    per_round, first = profile(root, cfg, rounds)
    campaign_id = Campaign(root, cfg).campaign_id
    quality = [(r.round, r.metrics.test, r.metrics.hard.get("auprc"))
               for r in read_rounds(root, campaign_id) if r.metrics]
    alone_s, alone_cpu_s, n_runs, lockstep_cpu_s = simulate_alone(
        root, campaign_id, cfg.scenario, DataRoot.resolve(tmp / "alone"))
    return {"campaign_id": campaign_id, "rounds": per_round, "first": first,
            "quality": quality, "alone": (alone_s, alone_cpu_s), "runs": n_runs,
            "lockstep": lockstep_cpu_s}


def report(cfg: CampaignConfig, result: dict) -> dict:
    """Print one campaign's tables; its summary (CPU seconds, ratios, last G_r's Test Set)."""
    print(f"\ncampaign {result['campaign_id']}: {cfg.scenario}, {cfg.strategy}, N_round "
          f"{cfg.n_round}, update {cfg.update}, epochs {cfg.epochs or 'default'}, "
          f"patience {cfg.patience or 'default'}")
    print("G_r's AUPRC (Test Set / Hard Set) by round: " + ", ".join(
        f"{r}: {_pct(t.get('auprc'))} / {_pct(h)}" for r, t, h in result["quality"]))
    rounds, first = result["rounds"], result["first"]
    wall = table("wall", [w for w, _ in rounds], first[0])
    cpu = table("CPU", [c for _, c in rounds], first[1])
    alone_s, alone_cpu_s = result["alone"]
    print(f"\nsimulate + log the same {result['runs']} runs alone: {alone_s:.2f} s wall, "
          f"{alone_cpu_s:.2f} s CPU one by one; {result['lockstep']:.2f} s CPU with the "
          f"lockstep engine, a round's runs together (campaign cost over it, rounds 1+: "
          f"{cpu['total'] / result['lockstep']:.2f}× CPU)")
    print(f"campaign cost, rounds 1+: {wall['total'] / alone_s:.2f}× wall, "
          f"{cpu['total'] / alone_cpu_s:.2f}× CPU (target ≤ {TARGET}×); with round 0: "
          f"{(wall['total'] + first[0]['total']) / alone_s:.2f}× wall, "
          f"{(cpu['total'] + first[1]['total']) / alone_cpu_s:.2f}× CPU")
    last = result["quality"][-1][1]
    return {"update": cfg.update, "seed": cfg.seed, "total": cpu["total"], "alone": alone_cpu_s,
            "train": cpu["train"], "wall": wall["total"], "alone_wall": alone_s,
            "lockstep": result["lockstep"],
            "auprc": last.get("auprc"), "auroc": last.get("auroc")}


def paired(diffs: list[float]) -> str:
    """Mean of paired differences (in points) with its 95 % t interval, the paired t-test's p and
    the minimum detectable effect at 80 % power over these pairs (what a null does not exclude)."""
    from scipy import stats

    from evoeye.evaluation.stats import minimum_detectable_effect

    d = 100 * np.asarray(diffs, float)
    if len(d) < 2:
        return f"{d.mean():+.2f}"
    sd = d.std(ddof=1)
    half = stats.t.ppf(0.975, len(d) - 1) * sd / np.sqrt(len(d))
    p = stats.ttest_1samp(d, 0.0).pvalue
    mde = minimum_detectable_effect(len(d), sd, test="t")
    return (f"{d.mean():+.2f} [{d.mean() - half:+.2f}, {d.mean() + half:+.2f}], p {p:.2f}, "
            f"MDE {mde:.2f}")


def summary(rows: list[dict], updates: list[str]) -> None:
    """Per mode: mean cost and ratios (over the runs simulated alone one by one, and over them
    stepped together as the campaign steps them); each mode's last Test AUPRC / AUROC against
    the first's."""
    print("\n| update | seeds | total CPU s | simulate alone CPU s | train CPU s | × alone (CPU) "
          "| × alone (wall) | × alone, lockstep (CPU) | Test AUPRC | paired Δ AUPRC vs "
          f"{updates[0]} [95 % CI], p, MDE | paired Δ AUROC [95 % CI], p, MDE |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = {r["seed"]: r for r in rows if r["update"] == updates[0]}
    for update in updates:
        mine = [r for r in rows if r["update"] == update]
        mean = {k: float(np.mean([r[k] for r in mine])) for k in
                ("total", "alone", "train", "wall", "alone_wall", "lockstep")}
        auprc = [r["auprc"] for r in mine if r["auprc"] is not None]
        both = [(r, base[r["seed"]]) for r in mine if r["seed"] in base]
        delta = "—" if update == updates[0] else paired(
            [a["auprc"] - b["auprc"] for a, b in both])
        delta_roc = "—" if update == updates[0] else paired(
            [a["auroc"] - b["auroc"] for a, b in both])
        print(f"| {update} | {','.join(str(r['seed']) for r in mine)} | {mean['total']:.2f} "
              f"| {mean['alone']:.2f} | {mean['train']:.2f} "
              f"| {mean['total'] / mean['alone']:.2f}× | {mean['wall'] / mean['alone_wall']:.2f}× "
              f"| {mean['total'] / mean['lockstep']:.2f}× "
              f"| {_pct(float(np.mean(auprc)) if auprc else None)} | {delta} | {delta_roc} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--root", type=Path, help="data root with initial runs and a G_0, split "
                    "as this script splits them (seed 0, train 0.5, val 0.25)")
    ap.add_argument("--update", nargs="+", default=["retrain"],
                    help="campaign option, MODE or MODE:EPOCHS, +keep for keep_parent (e.g. "
                    "warm:1+keep); several: one campaign each, compared with the first")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0], help="campaign seeds")
    ap.add_argument("--scenario", default="highway-cut-in")
    ap.add_argument("--strategy", default="evoeye")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--n-round", type=int, default=20)
    ap.add_argument("--epochs", type=int, help="campaign option (default: its own)")
    ap.add_argument("--patience", type=int, help="campaign option (default: its own)")
    ap.add_argument("--test-batch", help="a round-0 batch of the root held out as the Test Set")
    ap.add_argument("--runs", type=int, default=60, help="initial runs without --root")
    args = ap.parse_args()
    print(f"Machine: {describe()}; load average before: {os.getloadavg()[0]:.2f}")
    splits = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25, test_batch=args.test_batch)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-campaign-") as tmp:
        src = (DataRoot.existing(args.root) if args.root
               else seed_root(Path(tmp) / "seed", [args.scenario], args.runs, splits))
        for seed in args.seeds:
            for update in args.update:
                spec, keep, _ = update.partition("+keep")
                mode, _, epochs = spec.partition(":")
                cfg = CampaignConfig(args.scenario, strategy=args.strategy, budget_s=1e9,
                                     seed=seed, n_round=args.n_round, splits=splits,
                                     epochs=int(epochs) if epochs else args.epochs,
                                     patience=args.patience, update=mode,
                                     keep_parent=bool(keep))
                work = Path(tmp) / f"{mode}-{epochs}{'-keep' * bool(keep)}-s{seed}"
                rows.append({**report(cfg, run_one(src, cfg, args.rounds, work)),
                             "update": update})
                shutil.rmtree(work)
    if len(rows) > 1:
        summary(rows, args.update)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
