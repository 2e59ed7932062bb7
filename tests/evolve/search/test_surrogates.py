"""The surrogate strategies: boundary and disagreement pick where their target says, in batches."""

import numpy as np
import pytest

from evoeye.evolve.search import Records, StrategyError, make_strategy
from evoeye.evolve.search import surrogate as surrogate_module
from evoeye.evolve.search.boundary import COLLISION_MARGIN_M, signed_margin_m
from evoeye.evolve.search.fitness import criticality
from evoeye.scenarios import get_scenario

CROSSING = get_scenario("unprotected-intersection")  # 10 parameters
LEVEL = 0.8  # the planted failure boundary: u0 + u1 = LEVEL


def _planted(params):
    """A deterministic outcome: collision below the line u0 + u1 = LEVEL, the gap grows above."""
    u = CROSSING.normalise(params)
    s = u[..., 0] + u[..., 1] - LEVEL
    collided = s < 0
    return collided, criticality(collided, 20.0 * np.maximum(s, 0.0))


def _disagreement(params):
    """Monitors disagree in the corner u2, u3 < 0.25 (6 % of X), hardly anywhere else."""
    u = CROSSING.normalise(params)
    return np.where((u[..., 2] < 0.25) & (u[..., 3] < 0.25), 0.3, 0.01)


def _initial(n=40, seed=0):
    params = CROSSING.sample(np.random.default_rng(seed), n)
    collided, fitness = _planted(params)
    return Records(params, np.full(n, np.nan), fitness=fitness, collided=collided,
                   disagreement=_disagreement(params))


def _acquire(name, seed, n=100, **options):
    strategy, records = make_strategy(name, CROSSING, seed, **options), _initial(seed=seed)
    kinds = []
    for _ in range(n):
        prop = strategy.propose(records)
        collided, fitness = _planted(prop.x)
        records = records.append(prop.x, fitness=float(fitness), collided=bool(collided),
                                 disagreement=float(_disagreement(prop.x)))
        kinds.append(prop.kind)
    return records.tail(40), kinds


def test_the_signed_margin_is_the_gap_without_a_collision_and_negative_with_one():
    r = Records(np.zeros((3, 2)), np.zeros(3), fitness=criticality(
        np.array([True, False, False]), np.array([0.0, 2.5, 40.0])),
        collided=np.array([True, False, False]))
    np.testing.assert_allclose(signed_margin_m(r), [COLLISION_MARGIN_M, 2.5, 10.0])


def test_boundary_picks_concentrate_near_the_planted_boundary():
    """Mean distance of the acquired runs to the line u0 + u1 = LEVEL, boundary vs uniform."""
    def distance(records):
        u = CROSSING.normalise(records.params)
        return np.abs(u[:, 0] + u[:, 1] - LEVEL) / np.sqrt(2)

    near = {"boundary": [], "uniform": []}
    for seed in range(3):
        for name, dist in near.items():
            dist.append(distance(_acquire(name, seed)[0]).mean())
    assert np.mean(near["boundary"]) < 0.6 * np.mean(near["uniform"])


def test_boundary_keeps_a_quarter_of_each_batch_uniform():
    _, kinds = _acquire("boundary", seed=1, n=40)
    assert kinds.count("uniform") == 10 and kinds.count("boundary") == 30
    _, kinds = _acquire("boundary", seed=1, n=40, explore=0.5)
    assert kinds.count("uniform") == 20


def test_disagreement_acquires_where_the_monitors_disagree():
    share = {"disagreement": [], "uniform": []}
    for seed in range(3):
        for name, got in share.items():
            records, _ = _acquire(name, seed)
            got.append(np.mean(records.disagreement > 0.1))
    assert np.mean(share["disagreement"]) > np.mean(share["uniform"]) + 0.15


def test_without_a_target_a_batch_is_uniform():
    records = _initial()
    records = Records(records.params, records.feedback, fitness=records.fitness,
                      collided=records.collided)  # no disagreement known
    strategy = make_strategy("disagreement", CROSSING, seed=0)
    assert {strategy.propose(records).kind for _ in range(1)} == {"uniform"}


def test_a_surrogate_fits_once_per_batch(monkeypatch):
    fits = []
    real = surrogate_module.forest

    def counted(*args, **kwargs):
        fits.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(surrogate_module, "forest", counted)
    _acquire("boundary", seed=0, n=45, batch=20)
    assert len(fits) == 3  # batches 0, 1 and the first 5 proposals of 2


def test_a_batch_resumed_mid_way_is_the_batch_chosen_at_its_start():
    """After 25 proposals (batch 20), a fresh strategy replayed on them rebuilds batch 1 from
    the first n − 5 records and serves its 6th proposal."""
    init = _initial()
    a, records = make_strategy("boundary", CROSSING, seed=2), init
    for _ in range(25):
        x = a.propose(records).x
        collided, fitness = _planted(x)
        records = records.append(x, fitness=float(fitness), collided=bool(collided))
    b = make_strategy("boundary", CROSSING, seed=2)
    b.replay(records.tail(init.n).params, records.tail(init.n).fitness)
    np.testing.assert_array_equal(a.propose(records).x, b.propose(records).x)


def test_fewer_records_than_proposals_of_the_batch_is_an_error():
    strategy = make_strategy("boundary", CROSSING, seed=0)
    strategy.replay(CROSSING.sample(np.random.default_rng(0), 5), np.ones(5))
    with pytest.raises(StrategyError, match="record every proposal"):
        strategy.propose(Records.empty(CROSSING.dim))


def test_batch_and_explore_are_checked():
    with pytest.raises(StrategyError, match="batch"):
        make_strategy("boundary", CROSSING, seed=0, batch=0)
    with pytest.raises(StrategyError, match="explore"):
        make_strategy("disagreement", CROSSING, seed=0, explore=1.5)
