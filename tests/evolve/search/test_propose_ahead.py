"""`propose_ahead`: the proposals a loop may simulate together are exactly those it would have
proposed one at a time, recording and telling each before the next."""

import numpy as np
import pytest

from evoeye.evolve.search import STRATEGIES, Records, make_strategy
from evoeye.evolve.search.protocol import propose_ahead
from evoeye.evolve.search.registry import strategy_options
from evoeye.evolve.search.strategies import BatchedStrategy
from evoeye.scenarios import get_scenario

SPACE = get_scenario("highway-cut-in")
BATCH = 6
RUNS = 20


def _initial(n=12):
    params = SPACE.sample(np.random.default_rng(3), n)
    fit = _fitness(params)
    return Records(params, 1.0 - fit, fitness=fit, collided=fit < 0.25,
                   disagreement=np.linspace(0.0, 1.0, n))


def _fitness(params):
    """A synthetic criticality: low (critical) near one corner of the space."""
    return np.max(np.abs(SPACE.normalise(params) - 0.2), axis=-1)


def _record(strategy, records, prop):
    fit = float(_fitness(prop.x))
    strategy.tell(prop.x, fit)
    return records.append(prop.x, feedback=1.0 - fit, fitness=fit, collided=fit < 0.25,
                          disagreement=0.5, log_q=prop.log_q, log_p=prop.log_p)


def _make(name):
    return make_strategy(name, SPACE, 11, **strategy_options(name, batch=BATCH))


def _one_at_a_time(name, records):
    strategy, props = _make(name), []
    for _ in range(RUNS):
        props.append(strategy.propose(records))
        records = _record(strategy, records, props[-1])
    return props


def _ahead(name, records):
    strategy, props, sizes = _make(name), [], []
    while len(props) < RUNS:
        batch = strategy.propose_ahead(records, RUNS - len(props))
        sizes.append(len(batch))
        for prop in batch:  # simulated together, then told and recorded in order
            records = _record(strategy, records, prop)
        props += batch
    return props, sizes


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_proposals_ahead_are_the_ones_made_one_at_a_time(name):
    records = _initial()
    alone = _one_at_a_time(name, records)
    ahead, sizes = _ahead(name, records)
    assert sum(sizes) == RUNS and min(sizes) >= 1
    assert [p.kind for p in ahead] == [p.kind for p in alone]
    np.testing.assert_array_equal([p.x for p in ahead], [p.x for p in alone])
    assert [p.log_q for p in ahead] == [p.log_q for p in alone]
    # how far ahead each kind may go: every proposal, a batch, a generation, or one
    if name in ("uniform", "sobol"):
        assert sizes == [RUNS]
    elif isinstance(_make(name), BatchedStrategy):
        assert sizes == [BATCH] * (RUNS // BATCH) + [RUNS % BATCH]
    elif name == "avfuzzer":
        assert max(sizes) > 1
    else:  # density-aware: each proposal mutates the records as the last one left them
        assert sizes == [1] * RUNS


def test_a_batch_resumed_midway_goes_ahead_with_the_rest_of_it():
    records = _initial()
    first = _make("ce-is")
    props = [first.propose(records) for _ in range(2)]
    for prop in props:
        records = _record(first, records, prop)
    resumed = _make("ce-is")
    resumed.replay(records.params[-2:], records.fitness[-2:])
    rest = resumed.propose_ahead(records, RUNS)
    assert len(rest) == BATCH - 2
    np.testing.assert_array_equal([p.x for p in rest], [p.x for p in first.propose_ahead(
        records, RUNS)])


def test_a_pooled_strategy_goes_one_at_a_time():
    records = _initial()
    pooled = make_strategy("uniform", SPACE, 1, pool=SPACE.sample(np.random.default_rng(9), 40))
    assert len(pooled.propose_ahead(records, 10)) == 1


def test_a_strategy_that_cannot_say_is_asked_one_proposal_at_a_time():
    class Plain:  # a plug-in's strategy: the protocol without `propose_ahead`
        name = "plain"

        def __init__(self):
            self.inner = _make("uniform")

        def propose(self, records):
            return self.inner.propose(records)

    got = propose_ahead(Plain(), _initial(), 10)
    assert len(got) == 1
    np.testing.assert_array_equal(got[0].x, _make("uniform").propose(_initial()).x)
    assert len(propose_ahead(_make("uniform"), _initial(), 10)) == 10
