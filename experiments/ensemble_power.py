"""Does an ensemble of from-scratch members steady the study's learner? Its SDs and MDEs, k by k.

    nice -n 15 python -m experiments.ensemble_power --root DIR --members 1,3 --seeds 0-5 \\
        [--regime highway-cut-in] [--pool 600] [--test 300] [--val 200] \\
        [--val-collisions 0] [--checkpoints 80,160] [--out ensemble-power.json]

A small sample-efficiency study (pool mode, Uniform and `boundary`, no oracle, the per-round
monitor retrained, which the two strategies do not read: only the checkpoint monitors train)
on one data root, once per ensemble size k of `--members`: the regime's data is simulated
once and shared. Per checkpoint it reports the SD over seeds of Uniform's Test AUPRC, the SD of
the paired difference boundary − Uniform, the minimum detectable effect at 80 % power over the
seeds run and projected to 40 seeds (`evoeye.results.efficiency.power.detectable`), the CPU
seconds of each k's curves (a re-run finds them in the ledger: its CPU is not theirs), and
whether k members beat the first k (paired by seed). Each k's study page
(efficiency-k<k>.md, which states k) and the figures go beside `--out`.
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np

from evoeye.evaluation.stats import compare_paired
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import REFERENCE, EfficiencyConfig
from evoeye.results.efficiency.data import prepare_regime
from evoeye.results.efficiency.part import run_efficiency
from evoeye.results.efficiency.power import detectable
from evoeye.results.efficiency.report import efficiency_markdown
from evoeye.results.efficiency.summary import matrix
from evoeye.results.markdown import md_table

PROJECTED = 40  # seeds the MDE is projected to
STRATEGY = "boundary"


def cpu_s() -> float:
    """CPU seconds of this process and its finished children so far."""
    return sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                                  resource.getrusage(resource.RUSAGE_CHILDREN)))


def seeds_arg(text: str) -> tuple[int, ...]:
    """"0-5" or "0,1,2" → the seeds."""
    if "-" in text:
        first, last = map(int, text.split("-"))
        return tuple(range(first, last + 1))
    return tuple(int(s) for s in text.split(","))


def study_config(args: argparse.Namespace, members: int) -> EfficiencyConfig:
    return EfficiencyConfig(
        regimes=(args.regime,), mode="pool", update="retrain", strategies=(REFERENCE, STRATEGY),
        seeds=seeds_arg(args.seeds), oracle=False,
        checkpoints=tuple(int(c) for c in args.checkpoints.split(",")),
        reference_checkpoints=(), pool_runs=args.pool, test_runs=args.test, val_runs=args.val,
        oracle_runs=args.oracle_runs, boundary_pairs=args.boundary_pairs, members=members,
        val_collisions=args.val_collisions)


def spread(results: dict, config: EfficiencyConfig) -> dict[str, dict]:
    """Per checkpoint: Uniform's SD over seeds, and the paired boundary − Uniform figures."""
    curves = results["regimes"][config.regimes[0]]["curves"]
    budgets = config.checkpoints
    uniform = matrix(curves[REFERENCE], budgets, config.seeds)  # (seeds, budgets)
    other = matrix(curves[STRATEGY], budgets, config.seeds)
    out = {}
    for j, budget in enumerate(budgets):
        here = detectable(other[:, j], uniform[:, j])
        out[str(budget)] = {
            "uniform_mean": float(np.nanmean(uniform[:, j])),
            "uniform_sd": float(np.nanstd(uniform[:, j], ddof=1)),
            "diff_mean": float(np.nanmean(other[:, j] - uniform[:, j])),
            "diff_sd": here["sd_diff"], "correlation": here["correlation"], "n": here["n"],
            "mde": here["mde"],
            f"mde_{PROJECTED}": detectable(other[:, j], uniform[:, j], PROJECTED)["mde"],
            "uniform_by_seed": uniform[:, j].tolist(), "other_by_seed": other[:, j].tolist()}
    return out


def against_first(rows: dict[int, dict]) -> list[str]:
    """Did k members beat one? Per k after the first and checkpoint: Uniform's and the
    strategy's Test AUPRC with k members − with the first k, paired by seed (the same runs and
    member-0 seed), mean [95 % BCa CI] and the Wilcoxon p."""
    ks = list(rows)
    lines = []
    for k in ks[1:]:
        for budget, f in rows[k]["spread"].items():
            first = rows[ks[0]]["spread"][budget]
            cells = []
            for key in ("uniform_by_seed", "other_by_seed"):
                c = compare_paired(f[key], first[key])
                cells.append(f"{100 * c.mean_diff:+.1f} [{100 * c.ci_low:+.1f}, "
                             f"{100 * c.ci_high:+.1f}] p={c.p_value:.2g}")
            lines.append([f"{k} − {ks[0]}", budget, *cells])
    return md_table(["members", "runs", f"{REFERENCE} AUPRC difference",
                     f"{STRATEGY} AUPRC difference"], lines, numbers=False)


def table(rows: dict[int, dict]) -> list[str]:
    """The Markdown table of every k's figures (AUPRC points)."""
    lines = []
    for k, r in rows.items():
        for budget, f in r["spread"].items():
            lines.append([str(k), budget, f"{100 * f['uniform_mean']:.1f}",
                          f"{100 * f['uniform_sd']:.1f}",
                          f"{100 * f['diff_mean']:+.1f}", f"{100 * f['diff_sd']:.1f}",
                          f"{f['correlation']:.2f}", f"{100 * f['mde']:.1f}",
                          f"{100 * f[f'mde_{PROJECTED}']:.1f}", f"{r['cpu_s']:.0f}"])
    return md_table(["k", "runs", "Uniform AUPRC", "Uniform SD", f"{STRATEGY} − Uniform",
                     "paired SD", "correlation", "MDE (seeds run)", f"MDE at {PROJECTED} seeds",
                     "CPU s (all curves)"], lines, numbers=False)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, required=True)
    parser.add_argument("--members", default="1,3")
    parser.add_argument("--seeds", default="0-5")
    parser.add_argument("--regime", default="highway-cut-in")
    parser.add_argument("--pool", type=int, default=600)
    parser.add_argument("--test", type=int, default=300)
    parser.add_argument("--val", type=int, default=200)
    parser.add_argument("--oracle-runs", type=int, default=20)  # simulated, read by no curve
    parser.add_argument("--boundary-pairs", type=int, default=30)
    parser.add_argument("--val-collisions", type=int, default=0)
    parser.add_argument("--checkpoints", default="80,160")
    parser.add_argument("--out", type=Path, default=Path("ensemble-power.json"))
    args = parser.parse_args()
    root = DataRoot.resolve(args.root)
    ks = [int(k) for k in args.members.split(",")]
    t0, c0 = time.perf_counter(), cpu_s()
    prepare_regime(root, args.regime, study_config(args, ks[0]), say=print)
    out: dict = {"args": {k: str(v) for k, v in vars(args).items()},
                 "data": {"cpu_s": cpu_s() - c0, "wall_s": time.perf_counter() - t0},
                 "members": {}}
    for k in ks:
        config = study_config(args, k)
        t0, c0 = time.perf_counter(), cpu_s()
        results = run_efficiency(root, config, say=print)
        out["members"][k] = {"cpu_s": cpu_s() - c0, "wall_s": time.perf_counter() - t0,
                             "spread": spread(results, config)}
        args.out.with_name(f"efficiency-k{k}.md").write_text(efficiency_markdown(results),
                                                            encoding="utf-8")
        args.out.write_text(json.dumps(out, indent=1), encoding="utf-8")
    print("\n".join([*table(out["members"]), "", *against_first(out["members"])]))


if __name__ == "__main__":
    main()
