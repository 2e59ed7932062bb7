"""One curve of the testing-efficiency protocol: a strategy's runs at one seed of one regime.

A curve is a strategy simulating `runs` runs in memory (no log: the protocol keeps only what it
reports), proposal by proposal, told each outcome before its next batch. The proposals that wait
on no outcome (`propose_ahead`) are stepped together by the lockstep engine, whose runs are
`run_episode`'s bit for bit, so a curve is the same as when each run was simulated alone.

Every run keeps its θ, outcome, level (`risk_fitness`: what `ce-is` adapts on), proposal
densities (log q, log p: its exact weight p/q; NaN for a run drawn from p), and, for a
collision, its mechanism and root cause: the modules whose oracle alone avoids it
(`evoeye.sim.counterfactual`, the variants `evoeye explain` runs, re-simulated from the
factual episode already in memory).

Run seeds: run k of a curve has the seed SeedSequence([data_seed, crc(regime), crc(strategy),
seed, k]), so strategies share no run seed, and adding a regime or a strategy moves no other
curve's runs. The strategy itself is seeded with SeedSequence([data_seed, seed]): the pairing
is by seed. The same config gives the same runs, bit for bit.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable

import numpy as np

from evoeye.ads.profiles import ads_profile
from evoeye.criticality import peak_risk
from evoeye.evaluation.mechanism import mechanism
from evoeye.evolve.search.fitness import risk_fitness
from evoeye.evolve.search.protocol import propose_ahead
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.registry import make_strategy
from evoeye.results.efficiency.config import parse_regime
from evoeye.results.rare.config import RareConfig
from evoeye.scenarios import get_scenario
from evoeye.sim.counterfactual import ORACLES, VARIANTS, avoided_by
from evoeye.sim.episode import STATUS_OK, Episode
from evoeye.sim.lockstep import DEFAULT_BATCH, run_indexed
from evoeye.sim.runner import SimConfig, run_episode, run_spec

UNATTRIBUTED = "none"  # no single module's oracle avoids the collision


def _key(text: str) -> int:
    return zlib.crc32(text.encode())


def run_seed(config: RareConfig, regime: str, strategy: str, seed: int, k: int) -> int:
    """The run seed of run k of a curve (module doc)."""
    ss = np.random.SeedSequence([config.data_seed, _key(regime), _key(strategy), seed, k])
    return int(ss.generate_state(1)[0])


def strategy_seed(config: RareConfig, seed: int) -> int:
    return int(np.random.SeedSequence([config.data_seed, seed]).generate_state(1)[0])


def root_cause(factual: Episode) -> str:
    """The modules (in pipeline order, "+"-joined) whose oracle alone avoids the factual
    collision, or UNATTRIBUTED."""
    sim, ads = SimConfig(), ads_profile(factual.spec.ads)  # run_episode sets the cruise
    return "+".join(avoided_by([VARIANTS[v](factual, sim, ads) for v in ORACLES])) \
        or UNATTRIBUTED


def outcome_row(ep: Episode, explain: bool) -> dict:
    """A simulated run's row: its outcome, level and, for a collision, mechanism and root
    cause."""
    o = ep.outcome
    ok = o.status == STATUS_OK
    collided = bool(o.collided) and ok
    scenes = [f.scene for f in ep.frames]
    if collided:  # the level of the approach, not of the contact
        scenes = scenes[:max(int(round(o.collision_time_s * ep.rate_hz)), 1)]
    risk = peak_risk(scenes) if ok else float("nan")
    row = {"collided": collided, "ok": ok, "reason": o.reason, "risk": risk,
           "fitness": float(risk_fitness(collided, risk)), "min_gap_m": o.min_distance_m,
           "mechanism": None, "cause": None}
    if collided:
        m = mechanism(ep)
        row["mechanism"] = m.kind if m else None
        row["cause"] = root_cause(ep) if explain else None
    return row


def simulate(regime: str, x: np.ndarray, seed: int, explain: bool) -> dict:
    """One run, in memory (`run_episode`): its row (`outcome_row`)."""
    scenario, profile = parse_regime(regime)
    return outcome_row(run_episode(run_spec(scenario, x, seed, ads=profile)), explain)


def simulate_many(regime: str, xs: list[np.ndarray], seeds: list[int],
                  explain: bool) -> list[dict]:
    """`simulate` for each (x, seed), stepped together by the lockstep engine (the same runs,
    bit for bit); the rows in the order given."""
    scenario, profile = parse_regime(regime)
    specs = [run_spec(scenario, x, s, ads=profile) for x, s in zip(xs, seeds, strict=True)]
    rows: list[dict] = [{}] * len(specs)
    for i, ep in run_indexed(specs, size=DEFAULT_BATCH):
        rows[i] = outcome_row(ep, explain)
    return rows


def run_curve(config: RareConfig, regime: str, strategy: str, seed: int,
              on_run: Callable[[int], None] | None = None) -> dict:
    """Every run of one curve (module doc): {"x", "runs": [row], "log_q", "log_p"}. The
    proposals that do not wait on each other's outcome (`propose_ahead`: a Uniform curve's
    all, a batched strategy's batch) are simulated together."""
    space = get_scenario(parse_regime(regime)[0])
    strat = make_strategy(strategy, space, strategy_seed(config, seed),
                          **config.options(strategy))
    records = Records.empty(space.dim)
    rows: list[dict] = []
    while len(rows) < config.runs:
        props = propose_ahead(strat, records, config.runs - len(rows))
        ks = range(len(rows), len(rows) + len(props))
        simulated = simulate_many(regime, [p.x for p in props],
                                  [run_seed(config, regime, strategy, seed, k) for k in ks],
                                  config.explain)
        for k, prop, row in zip(ks, props, simulated, strict=True):
            strat.tell(prop.x, row["fitness"])
            records = records.append(prop.x, fitness=row["fitness"], collided=row["collided"],
                                     log_q=prop.log_q, log_p=prop.log_p)
            rows.append(row)
            if on_run:
                on_run(k)
    return {"x": records.params.tolist(), "runs": rows,
            "log_q": _json_floats(records.log_q), "log_p": _json_floats(records.log_p)}


def _json_floats(a: np.ndarray) -> list[float | None]:
    return [None if not np.isfinite(v) else float(v) for v in a]
