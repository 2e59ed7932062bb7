"""What the rare-failure protocol costs per simulated run, and where the time goes.

One curve per strategy at one seed of each regime, in this process (`time.process_time`, so
other load on the machine does not distort it): CPU seconds per run for the whole curve, and
its parts — the simulation alone (`run_episode`), the level (`criticality.peak_risk` over the
run's frames), and a collision's root cause (the four oracle re-simulations of
`runner.root_cause`, per collision). The protocol's cost on 2 cores is then
runs × CPU per run / 2 (its curves are independent, seed-major, in worker processes).

With `--compare`, each curve is also run one proposal at a time (the per-run engine, as
before the lockstep engine took the proposals that wait on no outcome, `propose_ahead`): its
CPU s per run, the saving, and whether the two curves are equal (they must be).

    python -m benchmarks.bench_rare [--runs 40] [--regime highway-cut-in:cautious ...] [--compare]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.machine import describe
from evoeye.criticality import peak_risk
from evoeye.results.efficiency.config import parse_regime
from evoeye.results.rare import runner
from evoeye.results.rare.config import REGIMES, RareConfig
from evoeye.results.rare.runner import root_cause, run_curve, run_seed
from evoeye.scenarios import get_scenario
from evoeye.sim.runner import run_episode, run_spec


def parts(regime: str, config: RareConfig, n: int) -> dict[str, float]:
    """CPU s per run of the simulation alone and of the level, over n uniform runs."""
    scenario, profile = parse_regime(regime)
    x = get_scenario(scenario).sample(np.random.default_rng(0), n)
    sim = risk = 0.0
    for k in range(n):
        t = time.process_time()
        ep = run_episode(run_spec(scenario, x[k], run_seed(config, regime, "bench", 0, k),
                                  ads=profile))
        t1 = time.process_time()
        peak_risk([f.scene for f in ep.frames])
        sim, risk = sim + t1 - t, risk + time.process_time() - t1
    return {"simulate": sim / n, "level": risk / n}


def explain_cost(regime: str, config: RareConfig, curve: dict) -> float | None:
    """CPU s of one collision's root cause (the curve's first collision), None without one."""
    scenario, profile = parse_regime(regime)
    hits = [k for k, r in enumerate(curve["runs"]) if r["collided"]]
    if not hits:
        return None
    k = hits[0]
    ep = run_episode(run_spec(scenario, curve["x"][k], run_seed(config, regime, "ce-is", 0, k),
                              ads=profile))
    t = time.process_time()
    root_cause(ep)
    return time.process_time() - t


def one_at_a_time(config: RareConfig, regime: str, strategy: str) -> tuple[dict, float]:
    """The curve with every proposal simulated alone, and its CPU s."""
    ahead = runner.propose_ahead
    runner.propose_ahead = lambda strat, records, n: [strat.propose(records)]
    try:
        t = time.process_time()
        return run_curve(config, regime, strategy, 0), time.process_time() - t
    finally:
        runner.propose_ahead = ahead


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=40)
    ap.add_argument("--regime", nargs="+", default=list(REGIMES))
    ap.add_argument("--strategies", nargs="+", help="default: the protocol's")
    ap.add_argument("--compare", action="store_true",
                    help="also run each curve one proposal at a time")
    a = ap.parse_args()
    print(describe())
    config = RareConfig(runs=a.runs, explain=False)
    print("| regime | strategy | runs | collisions | CPU s / run (curve) | simulate | level | "
          "root cause per collision | one at a time | × | equal |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for regime in a.regime:
        split = parts(regime, config, min(a.runs, 20))
        for strategy in a.strategies or config.strategies:
            t = time.process_time()
            curve = run_curve(config, regime, strategy, 0)
            per_run = (time.process_time() - t) / a.runs
            alone = "– | – | –"
            if a.compare:
                again, cpu = one_at_a_time(config, regime, strategy)
                alone = f"{cpu / a.runs:.3f} | {cpu / a.runs / per_run:.2f} | {again == curve}"
            hits = sum(r["collided"] for r in curve["runs"])
            cause = explain_cost(regime, config, curve) if strategy == "ce-is" else None
            print(f"| {regime} | {strategy} | {a.runs} | {hits} | {per_run:.3f} | "
                  f"{split['simulate']:.3f} | {split['level']:.4f} | "
                  f"{'–' if cause is None else f'{cause:.2f}'} | {alone} |", flush=True)


if __name__ == "__main__":
    main()
