"""Acquisition strategies by name: registry, ablations, determinism, resume from the records."""

import numpy as np
import pytest

from evoeye.evolve.search import (
    STRATEGIES,
    Records,
    Strategy,
    StrategyError,
    make_strategy,
    scenario_feedback,
)
from evoeye.evolve.search.mutation import EPSILON
from evoeye.scenarios import DEFAULT_DELTA, get_scenario

HIGHWAY = get_scenario("highway-cut-in")
CROSSING = get_scenario("unprotected-intersection")


def _initial(space, n=30, seed=0):
    rng = np.random.default_rng(seed)
    params = space.sample(rng, n)
    return Records(params, _oracle_feedback(space, params, version=0))


def _oracle_feedback(space, params, version):
    """A synthetic monitor error: high near a point that moves with each monitor version."""
    target = np.full(space.dim, 0.3 + 0.1 * version)
    return np.exp(-4.0 * np.max(np.abs(space.normalise(params) - target), axis=-1))


def _run(strategy, space, records, n, start=0):
    """A miniature Algorithm 1: propose, 'simulate', record; refresh feedback every 20 runs."""
    proposals = []
    for i in range(start, start + n):
        prop = strategy.propose(records)
        version = i // 20
        fb = float(_oracle_feedback(space, prop.x, version))
        strategy.tell(prop.x, 1.0 - fb)
        records = records.append(prop.x, feedback=fb, fitness=1.0 - fb, duration_s=20.0)
        if (i + 1) % 20 == 0:
            records = records.with_feedback(_oracle_feedback(space, records.params, version + 1))
        proposals.append(prop)
    return proposals, records


def test_registry_holds_the_paper_strategies_and_the_new_ones_and_each_is_a_strategy():
    assert set(STRATEGIES) == {"evoeye", "uniform", "avfuzzer", "no-feedback", "no-density",
                               "sobol", "boundary", "disagreement", "evoeye-knn",
                               "evoeye-forest", "ce-is", "subset", "subset-deep",
                               "subset-spread"}
    for name in STRATEGIES:
        strategy = make_strategy(name, CROSSING, seed=1)
        assert isinstance(strategy, Strategy)
        assert strategy.name == name


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(StrategyError, match=r"unknown acquisition strategy 'bayes'.*avfuzzer"):
        make_strategy("bayes", HIGHWAY, seed=0)


def test_density_strategies_need_initial_records():
    with pytest.raises(StrategyError, match="D_init"):
        make_strategy("evoeye", HIGHWAY, seed=0).propose(Records.empty(HIGHWAY.dim))


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_same_seed_and_results_give_the_same_proposals(name):
    a, _ = _run(make_strategy(name, HIGHWAY, seed=11), HIGHWAY, _initial(HIGHWAY), 45)
    b, _ = _run(make_strategy(name, HIGHWAY, seed=11), HIGHWAY, _initial(HIGHWAY), 45)
    c, _ = _run(make_strategy(name, HIGHWAY, seed=12), HIGHWAY, _initial(HIGHWAY), 45)
    np.testing.assert_array_equal([p.x for p in a], [p.x for p in b])
    assert [p.kind for p in a] == [p.kind for p in b]
    assert not np.array_equal([p.x for p in a], [p.x for p in c])


@pytest.mark.parametrize("name", sorted(STRATEGIES))
@pytest.mark.parametrize("crash_after", [1, 19, 20, 33])
def test_resume_from_the_records_continues_like_an_uninterrupted_run(name, crash_after):
    init = _initial(CROSSING)
    whole, _ = _run(make_strategy(name, CROSSING, seed=5), CROSSING, init, 60)
    first, records = _run(make_strategy(name, CROSSING, seed=5), CROSSING, init, crash_after)
    acquired = records.tail(init.n)  # what the loop's table holds for this strategy
    resumed = make_strategy(name, CROSSING, seed=5)
    resumed.replay(acquired.params, acquired.fitness)
    rest, _ = _run(resumed, CROSSING, records, 60 - crash_after, start=crash_after)
    np.testing.assert_array_equal([p.x for p in first + rest], [p.x for p in whole])


def test_no_feedback_ignores_feedback_and_always_mutates_locally():
    records = _initial(HIGHWAY)
    strategy = make_strategy("no-feedback", HIGHWAY, seed=2)
    np.testing.assert_array_equal(strategy.exploit_probabilities(records), np.ones(records.n))
    for _ in range(100):
        prop = strategy.propose(records)
        assert prop.kind == "local"
        assert HIGHWAY.distance(prop.x, records.params[prop.parent]) <= DEFAULT_DELTA + 1e-9


def test_no_density_uses_the_seed_feedback_alone():
    u = np.full((4, CROSSING.dim), 0.5)
    u[:, 0] = [0.0, 0.1, 0.25, 0.9]  # a, b, c share neighbourhoods; d is alone
    records = Records(CROSSING.denormalise(u), np.array([0.2, 0.6, 1.0, 0.4]))
    fbar = np.array([0.0, 0.5, 1.0, 0.25])
    p_seed = make_strategy("no-density", CROSSING, seed=0).exploit_probabilities(records)
    np.testing.assert_allclose(p_seed, (fbar + EPSILON) / (1 + EPSILON))
    p_full = make_strategy("evoeye", CROSSING, seed=0).exploit_probabilities(records)
    assert p_full[0] > 0.4 > p_seed[0]  # evoeye lifts a: its neighbour b has feedback


def test_uniform_ignores_the_records():
    a = make_strategy("uniform", HIGHWAY, seed=4)
    b = make_strategy("uniform", HIGHWAY, seed=4)
    for _ in range(10):
        x = a.propose(_initial(HIGHWAY, seed=1)).x
        np.testing.assert_array_equal(x, b.propose(_initial(HIGHWAY, seed=2)).x)


def test_evoeye_acquires_more_runs_where_the_monitor_errs_than_uniform():
    """A fixed error region ([0, 0.3]² on two axes, 9 % of X): evoeye exploits it, Uniform not."""

    def error(params):
        u = CROSSING.normalise(params)
        return np.where((u[..., 0] < 0.3) & (u[..., 1] < 0.3), 0.8, 0.1)

    mean_fb = {"evoeye": [], "uniform": []}
    for seed in range(5):
        params = CROSSING.sample(np.random.default_rng(seed), 40)
        for name, acquired in mean_fb.items():
            strategy, records = (
                make_strategy(name, CROSSING, seed=seed),
                Records(params, error(params)),
            )
            for _ in range(100):
                x = strategy.propose(records).x
                records = records.append(x, feedback=float(error(x)))
            acquired.append(records.tail(40).feedback.mean())
    assert np.mean(mean_fb["evoeye"]) > np.mean(mean_fb["uniform"]) + 0.02


def test_records_validate_their_columns():
    with pytest.raises(ValueError, match="feedback"):
        Records(np.zeros((3, 2)), np.zeros(2))
    r = Records.empty(2).append(np.ones(2), feedback=0.5, collided=True, duration_s=12.5)
    assert r.n == 1 and r.collided[0] and r.duration_s.sum() == 12.5 and np.isnan(r.fitness[0])


def test_feedback_refresh_aligns_by_scenario_id():
    r = Records.empty(2)
    for sid in ("run-b", "run-a", "run-c"):
        r = r.append(np.zeros(2), feedback=0.0, scenario_id=sid)
    # the new monitor's scores, context by context, in warehouse order
    fb = scenario_feedback(
        np.array([0.9, 0.1, 0.3]), np.array([0, 0, 1]), np.array(["run-a", "run-b", "run-a"])
    )
    refreshed = r.with_feedback(fb.aligned(r.scenario_id))
    np.testing.assert_allclose(refreshed.feedback, [0.1, 0.8, np.nan])  # run-c: no contexts
    assert list(refreshed.tail(1).scenario_id) == ["run-a", "run-c"]
