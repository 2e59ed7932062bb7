"""Density-aware mutation: S_δ, q_δ = μ_δ + σ_δ, p_δ, and the local/global draw."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evoeye.evolve.search import DensityIndex, Records, make_strategy, regional_potential
from evoeye.evolve.search.mutation import EPSILON, density_aware_mutation, exploit_probability
from evoeye.scenarios import DEFAULT_DELTA, SCENARIOS, get_scenario

CROSSING = get_scenario("unprotected-intersection")  # 10 parameters
HIGHWAY = get_scenario("highway-cut-in")  # 20 parameters


def _four_records():
    """Records spread along the first axis: a–b, b–c close (≤ δ), a–c and d far."""
    u = np.full((4, CROSSING.dim), 0.5)
    u[:, 0] = [0.0, 0.1, 0.25, 0.9]
    return u, np.array([0.2, 0.6, 1.0, 0.4])  # f̄ = [0, 0.5, 1, 0.25]


def test_potential_and_probability_match_a_hand_computation():
    u, f = _four_records()
    records = Records(CROSSING.denormalise(u), f)
    index = DensityIndex(DEFAULT_DELTA)
    index.update(CROSSING.normalise(records.params))
    assert [list(index.neighbours(i)) for i in range(4)] == [[0, 1], [0, 1, 2], [1, 2], [3]]
    # S(a) = {0, .5}: μ .25 σ .25; S(b) = {0, .5, 1}: μ .5 σ √(1/6); S(c) = {.5, 1}: μ .75 σ .25
    q_hand = np.array([0.5, 0.5 + np.sqrt(1 / 6), 1.0, 0.25])
    strategy = make_strategy("evoeye", CROSSING, seed=0)
    p = strategy.exploit_probabilities(records)
    np.testing.assert_allclose(p, (q_hand + EPSILON) / (1.0 + EPSILON), rtol=1e-9)
    np.testing.assert_allclose(regional_potential(u, np.array([0, 0.5, 1, 0.25])), q_hand)


def test_index_grown_record_by_record_equals_brute_force():
    rng = np.random.default_rng(4)
    centre = rng.uniform(0.2, 0.8, size=HIGHWAY.dim)
    u = np.vstack(
        [rng.uniform(size=(60, HIGHWAY.dim)), centre + rng.uniform(-0.12, 0.12, (90, 20))]
    )
    u = u[rng.permutation(len(u))]
    fbar = rng.uniform(size=len(u))
    fbar[::7] = np.nan  # unscored runs take no part in μ and σ
    index = DensityIndex(DEFAULT_DELTA)
    for n in (1, 2, 50, 51, 150):
        index.update(u[:n])
    d = np.max(np.abs(u[:, None, :] - u[None, :, :]), axis=-1)  # (n, n) Chebyshev
    q_brute = []
    for i in range(len(u)):
        near = fbar[(d[i] <= DEFAULT_DELTA) & np.isfinite(fbar)]
        q_brute.append(near.mean() + near.std() if len(near) else 0.0)
        assert list(index.neighbours(i)) == list(np.flatnonzero(d[i] <= DEFAULT_DELTA))
    np.testing.assert_allclose(index.potential(fbar), q_brute, atol=1e-12)
    assert index.n_pairs == int((d <= DEFAULT_DELTA).sum())


def test_index_rebuilds_when_records_are_not_an_append():
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(30, 4))
    u[:15] = 0.5 + rng.uniform(-0.05, 0.05, size=(15, 4))
    index = DensityIndex(0.2)
    index.update(u)
    reordered = u[::-1].copy()
    index.update(reordered)
    fresh = DensityIndex(0.2)
    fresh.update(reordered)
    fbar = rng.uniform(size=30)
    np.testing.assert_allclose(index.potential(fbar), fresh.potential(fbar))


def _cluster(rng, n, space, half_width=0.09):
    centre = np.full(space.dim, 0.5)
    return centre + rng.uniform(-half_width, half_width, size=(n, space.dim))


def test_dense_high_feedback_cluster_always_mutates_locally():
    rng = np.random.default_rng(1)
    u = _cluster(rng, 40, HIGHWAY)  # pairwise ≤ 0.18 < δ: one neighbourhood for everyone
    records = Records(HIGHWAY.denormalise(u), rng.uniform(0.6, 1.0, size=40))
    strategy = make_strategy("evoeye", HIGHWAY, seed=3)
    np.testing.assert_array_equal(strategy.exploit_probabilities(records), np.ones(40))
    for _ in range(300):
        prop = strategy.propose(records)
        assert prop.kind == "local" and prop.p_local == 1.0
        gap = HIGHWAY.distance(prop.x, records.params[prop.parent])
        assert gap <= DEFAULT_DELTA + 1e-9


def _cluster_and_loners(rng, loner_feedback):
    """A high-feedback cluster plus far-apart single records with the given raw feedback."""
    cluster = _cluster(rng, 30, CROSSING)
    loners = np.full((len(loner_feedback), CROSSING.dim), 0.05)
    for i in range(len(loners)):
        loners[i, i] = 0.95  # loners differ by 0.9 on two axes from each other
    u = np.vstack([cluster, loners])
    f = np.concatenate([np.ones(30), loner_feedback])
    return Records(CROSSING.denormalise(u), f)


def test_zero_feedback_seed_explores_globally_at_the_rate_p():
    records = _cluster_and_loners(np.random.default_rng(2), np.array([0.0, 0.3, 0.0]))
    p = make_strategy("evoeye", CROSSING, seed=0).exploit_probabilities(records)
    assert p[:30] == pytest.approx(1.0)
    assert p[30] == pytest.approx(EPSILON / (1 + EPSILON))  # empty-feedback neighbourhood
    assert p[31] == pytest.approx((0.3 + EPSILON) / (1 + EPSILON))
    rng = np.random.default_rng(5)
    for seed_row in (30, 31):
        draws = [
            density_aware_mutation(CROSSING, records.params[seed_row], p[seed_row], rng)
            for _ in range(4000)
        ]
        local = np.array([m.local for m in draws])
        tol = 4 * np.sqrt(p[seed_row] * (1 - p[seed_row]) / 4000) + 1e-3
        assert abs(local.mean() - p[seed_row]) <= tol
        gaps = CROSSING.distance(np.array([m.x for m in draws]), records.params[seed_row])
        assert (gaps[local] <= DEFAULT_DELTA + 1e-9).all()
        assert (gaps[~local] > DEFAULT_DELTA).mean() > 0.99  # global draws land elsewhere


def test_exploit_probability_is_one_at_the_max_and_defined_when_all_zero():
    np.testing.assert_allclose(exploit_probability(np.array([0.0, 0.5, 2.0]))[2], 1.0)
    np.testing.assert_array_equal(exploit_probability(np.zeros(3)), np.ones(3))


@settings(max_examples=60, deadline=None)
@given(
    name=st.sampled_from(["evoeye", "no-feedback", "no-density", "uniform"]),
    scenario=st.sampled_from(sorted(SCENARIOS)),
    n=st.integers(1, 25),
    seed=st.integers(0, 2**32 - 1),
    edge=st.booleans(),
)
def test_proposals_always_lie_inside_the_space(name, scenario, n, seed, edge):
    space = get_scenario(scenario)
    rng = np.random.default_rng(seed)
    u = rng.uniform(size=(n, space.dim))
    if edge:  # records on the boundary of the ranges, where N_δ must be clipped
        u = np.round(u)
    f = rng.uniform(size=n)
    f[rng.uniform(size=n) < 0.2] = np.nan
    records = Records(space.denormalise(u), f)
    strategy = make_strategy(name, space, seed=seed % 1000)
    for _ in range(5):
        x = strategy.propose(records).x
        assert x.shape == (space.dim,)
        space.validate(x)  # raises outside [low, high]
