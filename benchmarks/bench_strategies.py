"""What a round's proposals cost each acquisition strategy: fit + score + pick for N_round runs.

Synthetic records (uniform θ, a planted collision boundary, a feedback and a disagreement that
depend on θ) of each logical scenario's dimension, n records already in D_r, then one round of
N_round = 20 proposals, each recorded before the next as the loop does; the figure is this
process's CPU seconds (`time.process_time`) for the round, median of `--repeat`. The target: a
surrogate's fit and pick under 10 % of a round's simulation (20 runs ≈ 7 s CPU on highway-cut-in,
BENCHMARKS.md "A campaign's cost"), i.e. < 0.7 s. `--pool M` also times pool mode, the round
picked among M pre-simulated candidates.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from benchmarks.machine import describe
from evoeye.evolve.search import Records, make_strategy
from evoeye.evolve.search.fitness import criticality
from evoeye.scenarios import get_scenario

STRATEGIES = ("uniform", "sobol", "evoeye", "evoeye-knn", "evoeye-forest", "boundary",
              "disagreement")
SIMULATION_S = 7.0  # CPU seconds of a round of 20 highway runs (BENCHMARKS.md)


def synthetic(space, params: np.ndarray) -> dict[str, np.ndarray]:
    """Outcome columns of a planted world: collision below u0 + u1 = 0.8, errors near it."""
    u = space.normalise(params)
    s = u[:, 0] + u[:, 1] - 0.8
    collided = s < 0
    return {"fitness": criticality(collided, 20.0 * np.maximum(s, 0.0)), "collided": collided,
            "feedback": np.exp(-8.0 * np.abs(s)), "disagreement": 0.2 * np.exp(-8.0 * np.abs(s))}


def round_cpu_s(name: str, scenario: str, n: int, n_round: int, pool: int | None,
                seed: int) -> float:
    """CPU seconds of one round of `n_round` proposals after `n` records."""
    space = get_scenario(scenario)
    rng = np.random.default_rng(seed)
    candidates = space.sample(rng, pool) if pool else None
    params = candidates[:n] if pool else space.sample(rng, n)
    records = Records(params, **synthetic(space, params))
    strategy = make_strategy(name, space, seed, pool=candidates)
    t0 = time.process_time()
    for _ in range(n_round):
        x = strategy.propose(records).x
        out = {k: float(v[0]) for k, v in synthetic(space, x[None, :]).items()}
        strategy.tell(x, out["fitness"])
        records = records.append(x, **out)
    return time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--records", type=int, nargs="+", default=[100, 500, 2000])
    ap.add_argument("--scenario", nargs="+", default=["highway-cut-in",
                                                      "unprotected-intersection"])
    ap.add_argument("--strategy", nargs="+", default=list(STRATEGIES))
    ap.add_argument("--n-round", type=int, default=20)
    ap.add_argument("--pool", type=int, default=None, help="Also time pool mode over M rows.")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"machine: {describe()}; load average {os.getloadavg()[0]:.1f}; CPU s per round of "
          f"{args.n_round} proposals, median of {args.repeat}; share of a round's simulation "
          f"({SIMULATION_S:.0f} s)\n")
    modes = [None] + ([args.pool] if args.pool else [])
    print("| scenario | records | mode | " + " | ".join(args.strategy) + " |")
    print("|---|---|---|" + "---|" * len(args.strategy))
    for scenario in args.scenario:
        for n in args.records:
            for pool in modes:
                cells = []
                for name in args.strategy:
                    cpu = statistics.median(round_cpu_s(name, scenario, n, args.n_round, pool,
                                                        seed) for seed in range(args.repeat))
                    cells.append(f"{cpu:.3f} ({100 * cpu / SIMULATION_S:.1f} %)")
                mode = f"pool {pool}" if pool else "free"
                print(f"| {scenario} | {n} | {mode} | " + " | ".join(cells) + " |", flush=True)
        print(f"load average after {scenario}: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
