"""Pool mode: every strategy picks unused rows of a finite pool, each once, resumably."""

import numpy as np
import pytest

from evoeye.evolve.search import (
    GENERATIVE_ONLY,
    STRATEGIES,
    CandidatePool,
    Records,
    StrategyError,
    make_strategy,
)
from evoeye.evolve.search.fitness import criticality
from evoeye.scenarios import get_scenario

CROSSING = get_scenario("unprotected-intersection")  # 10 parameters
POOL = CROSSING.sample(np.random.default_rng(99), 400)
INIT = POOL[:30]  # D_init taken from the pool too: those rows are never proposed
POOLABLE = sorted(set(STRATEGIES) - GENERATIVE_ONLY)  # the others refuse a pool (their tests)


def _outcome(x):
    u = CROSSING.normalise(x)
    collided = u[..., 0] + u[..., 1] < 0.7
    fitness = criticality(collided, 20.0 * np.maximum(u[..., 0] + u[..., 1] - 0.7, 0.0))
    return collided, fitness, 1.0 - fitness


def _records(params):
    collided, fitness, feedback = _outcome(params)
    return Records(params, feedback, fitness=fitness, collided=collided,
                   disagreement=feedback * 0.5)


def _run(strategy, records, n):
    """The pool-based screening loop: take the chosen row's pre-simulated outcome."""
    props = []
    for _ in range(n):
        prop = strategy.propose(records)
        row = POOL[prop.pool_index]
        collided, fitness, feedback = _outcome(row)
        records = records.append(row, feedback=float(feedback), fitness=float(fitness),
                                 collided=bool(collided), disagreement=float(feedback) * 0.5)
        strategy.tell(row, float(fitness))
        props.append(prop)
    return props, records


@pytest.mark.parametrize("name", POOLABLE)
def test_pool_mode_picks_each_unused_row_once_and_says_which(name):
    props, records = _run(make_strategy(name, CROSSING, seed=4, pool=POOL), _records(INIT), 60)
    picked = [p.pool_index for p in props]
    assert len(set(picked)) == 60
    assert min(picked) >= len(INIT)  # never a row D_init holds
    for p in props:
        np.testing.assert_array_equal(p.x, POOL[p.pool_index])


@pytest.mark.parametrize("name", POOLABLE)
def test_pool_mode_is_deterministic_and_resumes_from_the_records(name):
    whole, _ = _run(make_strategy(name, CROSSING, seed=7, pool=POOL), _records(INIT), 50)
    first, records = _run(make_strategy(name, CROSSING, seed=7, pool=POOL), _records(INIT), 27)
    resumed = make_strategy(name, CROSSING, seed=7, pool=POOL)
    mine = records.tail(len(INIT))
    resumed.replay(mine.params, mine.fitness)
    rest, _ = _run(resumed, records, 23)
    assert [p.pool_index for p in first + rest] == [p.pool_index for p in whole]


def test_uniform_in_pool_mode_draws_rows_uniformly_not_by_voronoi_cell():
    """Every unused row is equally likely: over many seeds, the first pick's row index is
    spread evenly over the pool (a snap of uniform θ would favour isolated rows)."""
    pool = np.vstack([np.full((1, CROSSING.dim), 0.5), np.full((99, CROSSING.dim), 0.9)])
    pool = CROSSING.denormalise(pool + np.linspace(0, 0.05, 100)[:, None])
    firsts = [make_strategy("uniform", CROSSING, seed=s, pool=pool).propose(
        Records.empty(CROSSING.dim)).pool_index for s in range(300)]
    assert firsts.count(0) < 15  # 3 expected; snapping would give row 0 most draws


def test_a_surrogate_in_pool_mode_scores_the_rows():
    """boundary on a pool: its model picks sit nearer the planted boundary than the pool does."""
    props, _ = _run(make_strategy("boundary", CROSSING, seed=1, pool=POOL), _records(INIT), 60)
    u = CROSSING.normalise(POOL)
    dist = np.abs(u[:, 0] + u[:, 1] - 0.7)
    model = [p.pool_index for p in props if p.kind == "boundary"]
    assert len(model) == 45
    assert dist[model].mean() < 0.6 * dist[len(INIT):].mean()


def test_a_used_up_pool_is_an_error_naming_it():
    strategy = make_strategy("evoeye", CROSSING, seed=0, pool=POOL[:35])
    _, records = _run(strategy, _records(INIT), 5)
    with pytest.raises(StrategyError, match="pool of 35 candidates is used up"):
        strategy.propose(records)


def test_avfuzzer_in_pool_mode_may_have_a_batch_in_flight_without_repeats():
    strategy = make_strategy("avfuzzer", CROSSING, seed=0, pool=POOL)
    records = _records(INIT)
    in_flight = [strategy.propose(records) for _ in range(strategy.available())]
    assert len({p.pool_index for p in in_flight}) == len(in_flight) == 4
    for p in in_flight:
        strategy.tell(p.x, float(_outcome(p.x)[1]))
    with pytest.raises(StrategyError, match="not in flight"):
        strategy.tell(POOL[0], 0.5)


def test_a_pool_outside_the_space_or_of_the_wrong_shape_is_refused():
    with pytest.raises(StrategyError, match="outside the ranges"):
        CandidatePool(CROSSING, np.vstack([POOL[:3], CROSSING.high + 1.0]))
    with pytest.raises(StrategyError, match=r"\(m, 10\)"):
        CandidatePool(CROSSING, POOL[:, :4])
