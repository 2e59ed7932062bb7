"""A small demonstration of `ce-is` against Uniform where failures are rare: failures found per
100 simulated runs, and the failure-rate estimate each strategy's runs give.

    python -m experiments.ce_is_demo [--scenario highway-cut-in] [--ads cautious] \\
        [--seeds 0,1,2,3] [--initial 40] [--runs 200] [--reference 1000] [--out FILE]

Per seed: D_init is `--initial` uniform runs (shared by both strategies), then each strategy
acquires `--runs` runs in batches of 20, simulated in memory (no log, no monitor: only the
outcome and the footprint gap the strategies read). Uniform's estimate of P(collision) is the
share that collided; ce-is's the importance-sampling one from its runs' exact p/q
(`evoeye.evaluation.failure_rate`). `--reference` uniform runs of their own seed give the
failure rate the estimates should find. Every finished unit (a seed's strategy, the reference)
is written to `--out` at once, and a re-run skips it: a killed demonstration resumes. Not the
issue's protocol (no learning curves, a handful of seeds): a demonstration of what the strategy
is for.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from evoeye.evaluation.failure_rate import failure_rate
from evoeye.evolve.search.fitness import criticality
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.registry import make_strategy
from evoeye.scenarios import get_scenario
from evoeye.sim.runner import run_episode, run_spec

STRATEGIES = ("uniform", "ce-is")
BATCH = 20


def simulate(scenario: str, ads: str, x: np.ndarray, seed: int) -> tuple[bool, float]:
    """(collided, criticality) of one run, simulated in memory."""
    out = run_episode(run_spec(scenario, x, seed, ads=ads)).outcome
    collided = bool(out.collided) and out.status == "ok"
    gap = np.nan if out.min_distance_m is None else out.min_distance_m
    return collided, float(criticality(collided, gap))


def run_seed_of(*key: int) -> int:
    return int(np.random.SeedSequence(list(key)).generate_state(1)[0])


def initial(scenario: str, ads: str, seed: int, n: int) -> Records:
    space = get_scenario(scenario)
    x = space.sample(np.random.default_rng([seed, 10_000]), n)
    rows = [simulate(scenario, ads, xi, run_seed_of(seed, 10_000, i)) for i, xi in enumerate(x)]
    collided, fitness = map(np.array, zip(*rows, strict=True))
    return Records(x, np.full(n, np.nan), fitness=fitness, collided=collided)


def acquire(scenario: str, ads: str, name: str, seed: int, records: Records, n: int) -> dict:
    """A strategy's n runs after D_init `records`: outcomes, p/q, and what they give."""
    space = get_scenario(scenario)
    strategy = make_strategy(name, space, seed, batch=BATCH) if name == "ce-is" else \
        make_strategy(name, space, seed)
    n_init = records.n
    for k in range(n):
        prop = strategy.propose(records)
        collided, fit = simulate(scenario, ads, prop.x,
                                 run_seed_of(seed, STRATEGIES.index(name) + 1, k))
        strategy.tell(prop.x, fit)
        records = records.append(prop.x, fitness=fit, collided=collided, log_q=prop.log_q,
                                 log_p=prop.log_p)
    mine = records.tail(n_init)
    rate = failure_rate(mine.collided, mine.importance_ratio())
    return {"runs": n, "collisions": int(mine.collided.sum()),
            "per_100": 100.0 * float(mine.collided.mean()), "estimate": rate.to_dict(),
            "max_ratio": float(mine.importance_ratio().max())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="highway-cut-in")
    ap.add_argument("--ads", default="cautious")
    ap.add_argument("--seeds", default="0,1,2,3")
    ap.add_argument("--initial", type=int, default=40)
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--reference", type=int, default=1000)
    ap.add_argument("--out", type=Path, default=Path("ce-is-demo.json"))
    a = ap.parse_args()
    done = json.loads(a.out.read_text()) if a.out.exists() else {}

    def keep(key: str, make) -> dict:
        if key not in done:
            done[key] = make()
            a.out.write_text(json.dumps(done, indent=1))
            print(key, json.dumps(done[key]), flush=True)
        return done[key]

    for seed in (int(s) for s in a.seeds.split(",")):
        init = None
        for name in STRATEGIES:
            if f"{seed}/{name}" in done:
                continue
            init = init or initial(a.scenario, a.ads, seed, a.initial)
            keep(f"{seed}/{name}", lambda name=name, init=init, seed=seed: acquire(
                a.scenario, a.ads, name, seed, init, a.runs))
    if a.reference:
        def reference() -> dict:
            space = get_scenario(a.scenario)
            x = space.sample(np.random.default_rng([1_000_000, 1]), a.reference)
            hits = [simulate(a.scenario, a.ads, xi, run_seed_of(1_000_000, i))[0]
                    for i, xi in enumerate(x)]
            return failure_rate(hits, np.ones(len(hits))).to_dict()

        keep("reference", reference)


if __name__ == "__main__":
    main()
