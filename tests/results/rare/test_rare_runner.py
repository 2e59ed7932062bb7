"""A rare-failure curve: deterministic by its config, seeded apart per strategy, and a
collision's root cause the same as `evoeye explain`'s counterfactuals give."""

from __future__ import annotations

import numpy as np

from evoeye.criticality import Criticality, FrameRisk, peak_risk
from evoeye.evolve.search.fitness import risk_fitness
from evoeye.results.rare.config import RareConfig
from evoeye.results.rare.runner import ORACLES, root_cause, run_curve, run_seed, simulate
from evoeye.sim.counterfactual import explain_run
from evoeye.sim.runner import run_episode, run_spec

# a cautious-stack highway run that collides (found by a uniform screen of 1 000 runs)
COLLISION_X = [28.241725372308697, 41.07900303800834, 16.96187873601694, 9.835974862916274,
               5.172919422497342, 5.052250238503923, 94.97510303254442, 23.838451494667858,
               27.026119718672913, 3.678678258377584, 71.71700410970445, 15.636828851701475,
               49.0850112800216, 4.930144944112402, -31.075109532938704, 30.99081557092344,
               -35.38244348421124, 28.67990642366096, -62.34206311309097, 25.64912570774719]
COLLISION_SEED = 100034
REGIME = "highway-cut-in:cautious"


def test_risk_ratio_is_one_at_the_critical_bounds_and_above_it_when_critical():
    c = Criticality()
    risk = FrameRisk(np.array([np.inf, 3.0, 1.5, 0.75]), np.array([0.0, 1.0, 4.0, 2.0]))
    assert risk.ratio(c).tolist() == [0.0, 0.5, 1.0, 2.0]
    assert (risk.ratio(c) > 1.0).tolist() == risk.critical(c).tolist()  # the bounds are strict


def test_risk_fitness_orders_runs_by_how_near_they_came():
    fit = risk_fitness(np.array([True, False, False, False]),
                       np.array([5.0, 3.0, 0.5, np.nan]))
    assert fit.tolist() == [0.0, 0.25, 1.0 / 1.5, 1.0]


def test_a_curve_is_the_same_twice_and_differs_by_seed():
    config = RareConfig(seeds=(0, 1), runs=4, batch=2, explain=False)
    a = run_curve(config, REGIME, "ce-is", 0)
    assert a == run_curve(config, REGIME, "ce-is", 0)
    b = run_curve(config, REGIME, "ce-is", 1)
    assert a["x"] != b["x"]
    assert all(q is not None for q in a["log_q"])  # every ce-is run carries its density
    u = run_curve(config, REGIME, "uniform", 0)
    assert all(q is None for q in u["log_q"])  # drawn from p: weight 1
    assert {run_seed(config, REGIME, "uniform", 0, k) for k in range(4)}.isdisjoint(
        {run_seed(config, REGIME, "ce-is", 0, k) for k in range(4)})


def test_a_curve_stepped_in_lockstep_has_the_rows_of_its_runs_simulated_one_by_one():
    config = RareConfig(seeds=(0, 1), runs=6, batch=2, explain=True)
    curve = run_curve(config, REGIME, "uniform", 0)
    alone = [simulate(REGIME, np.array(x), run_seed(config, REGIME, "uniform", 0, k), True)
             for k, x in enumerate(curve["x"])]
    assert curve["runs"] == alone


def test_a_collision_gets_its_mechanism_and_the_explain_root_cause():
    row = simulate(REGIME, np.array(COLLISION_X), COLLISION_SEED, explain=True)
    assert row["collided"] and row["fitness"] == 0.0 and row["mechanism"]
    ex = explain_run(run_spec("highway-cut-in", COLLISION_X, COLLISION_SEED, ads="cautious"))
    by = {v.variant: v for v in ex.variants}
    avoided = [o.removeprefix("oracle_") for o in ORACLES if not by[o].collided]
    assert row["cause"] == ("+".join(avoided) or "none")
    ep = run_episode(run_spec("highway-cut-in", COLLISION_X, COLLISION_SEED, ads="cautious"))
    assert root_cause(ep) == row["cause"]
    k = int(round(ep.outcome.collision_time_s * ep.rate_hz))
    assert row["risk"] == peak_risk([f.scene for f in ep.frames[:k]]) >= 1.0
