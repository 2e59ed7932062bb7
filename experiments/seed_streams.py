"""Do the seed streams of batches, Test Sets and campaigns meet? A scan of run ids.

    python -m experiments.seed_streams [--scenario highway-cut-in] [--runs 2000] \\
        [--test-runs 400] [--seeds 0,1,2] [--proposals 100] [--old]

Plans the root's initial batch (`--runs` at seed 0, as `evoeye simulate` does) and its Test Set
(`--test-runs` at seed 1 000 000), then drives a campaign of every registered strategy at every
seed of `--seeds` for `--proposals` proposals on those initial runs, and counts the run ids
that occur twice. A run id is a hash of (scenario, vector, run seed), so no simulation is
needed: each proposal is told a synthetic outcome, a smooth function of its vector (which only
steers the feedback-reading strategies; the streams are what is scanned). `--old` draws the
campaigns from the streams before `evoeye.seeds` (strategy seed s, run seed `[s, k]`).
The vectors and seeds are drawn by the same functions a campaign calls (`evoeye.seeds`,
`make_strategy`, `run_spec`); the redraw guard is left out, so a repeat here is a stream
meeting another.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter

import numpy as np

from evoeye.batch import plan_uniform
from evoeye.evolve.campaign.state import run_seed
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.registry import STRATEGIES, make_strategy, strategy_options
from evoeye.scenarios import get_scenario
from evoeye.seeds import campaign_run_seed, search_seed
from evoeye.sim.runner import run_spec

TEST_SEED = 1_000_000


def _outcome(u: np.ndarray) -> tuple[float, float]:
    """(fitness, feedback) of a normalised vector: deterministic, smooth, both in [0, 1]."""
    fitness = float(np.clip(abs(np.sin(3.0 * u.sum())), 0.0, 1.0))
    return fitness, float(0.5 + 0.5 * np.cos(5.0 * u[0] + 2.0 * u[-1]))


def campaign_ids(scenario: str, strategy: str, seed: int, initial: np.ndarray,
                 proposals: int, old: bool = False) -> list[str]:
    """The run ids of a campaign's first `proposals` proposals on D_init = `initial` (n, dim)."""
    space = get_scenario(scenario)
    outcomes = [_outcome(u) for u in space.normalise(initial)]
    records = Records(params=initial, feedback=np.array([f for _, f in outcomes]),
                      fitness=np.array([c for c, _ in outcomes]),
                      disagreement=np.array([f for _, f in outcomes]))
    campaign = f"evo-{strategy}-s{seed}"  # stands for its id (a hash of its whole config)
    strat = make_strategy(strategy, space, seed if old else search_seed(seed, campaign),
                          **strategy_options(strategy, delta=0.2, batch=20))
    ids = []
    for k in range(proposals):
        x = strat.propose(records).x
        run = run_seed(seed, k) if old else campaign_run_seed(seed, campaign, k)
        ids.append(run_spec(scenario, x, run).scenario_id)
        fitness, feedback = _outcome(space.normalise(x))
        strat.tell(x, fitness)
        records = records.append(x, feedback=feedback, fitness=fitness, disagreement=feedback)
    return ids


def scan(scenario: str, runs: int, test_runs: int, seeds: list[int], proposals: int,
         old: bool = False) -> dict:
    """Every planned run id by where it came from, and the ids that occur more than once."""
    initial = plan_uniform(scenario, runs, 0)
    sources = {"uniform-seed0": [s.scenario_id for s in initial]}
    if test_runs:
        sources[f"test-seed{TEST_SEED}"] = [
            s.scenario_id for s in plan_uniform(scenario, test_runs, TEST_SEED)]
    params = np.array([s.params for s in initial], float)
    for strategy in STRATEGIES:
        for seed in seeds:
            sources[f"{strategy}-s{seed}"] = campaign_ids(scenario, strategy, seed, params,
                                                          proposals, old)
    counts = Counter(i for ids in sources.values() for i in ids)
    repeated = sorted(i for i, n in counts.items() if n > 1)
    where = {i: sorted(name for name, ids in sources.items() if i in ids) for i in repeated}
    return {"runs": sum(counts.values()), "distinct": len(counts),
            "repeated": len(repeated), "where": where}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="highway-cut-in")
    ap.add_argument("--runs", type=int, default=2000)
    ap.add_argument("--test-runs", type=int, default=400)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--proposals", type=int, default=100)
    ap.add_argument("--old", action="store_true", help="the streams before evoeye.seeds")
    a = ap.parse_args(argv)
    out = scan(a.scenario, a.runs, a.test_runs, [int(s) for s in a.seeds.split(",")],
               a.proposals, a.old)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
