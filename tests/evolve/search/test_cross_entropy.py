"""`ce-is`: exact, bounded densities; the CE update moves towards the failures; resume; pool."""

import numpy as np
import pytest

from evoeye.evolve.search import Records, StrategyError, make_strategy
from evoeye.evolve.search.cross_entropy import (
    ALPHA,
    BetaProduct,
    DefensiveMixture,
    ce_update,
    elite,
)
from evoeye.scenarios import LogicalScenario, Parameter, get_scenario

TOY = LogicalScenario("toy", "a 4-D box", tuple(
    Parameter(f"p{i}", 10.0 * i, 10.0 * i + 2.0 + i, "m", "") for i in range(4)))
HIGHWAY = get_scenario("highway-cut-in")


def criticality(space, x):
    """Synthetic: 0 (a collision) in the corner u0 > 0.8, u1 < 0.2 (p-mass 0.04), rising
    linearly away from it."""
    u = space.normalise(x)
    gap = np.maximum(0.8 - u[..., 0], 0) + np.maximum(u[..., 1] - 0.2, 0)
    return np.clip(1.5 * gap, 0.0, 1.0)


def acquire(name, space, seed, n, n_init=40):
    strategy = make_strategy(name, space, seed)
    init = space.sample(np.random.default_rng([seed, 99]), n_init)
    f = criticality(space, init)
    records = Records(init, np.full(n_init, np.nan), fitness=f, collided=f == 0)
    props = []
    for _ in range(n):
        prop = strategy.propose(records)
        f = float(criticality(space, prop.x))
        strategy.tell(prop.x, f)
        records = records.append(prop.x, fitness=f, collided=f == 0, log_q=prop.log_q,
                                 log_p=prop.log_p)
        props.append(prop)
    return strategy, records, props


def test_the_mixture_is_a_density_bounded_below_by_alpha():
    q = DefensiveMixture(ALPHA, BetaProduct(np.array([0.9, 0.2, 0.5]),
                                            np.array([0.05, 0.1, 0.2])))
    u = np.random.default_rng(0).uniform(size=(200_000, 3))
    density = np.exp(q.log_q(u))
    assert density.min() >= ALPHA - 1e-12  # p/q <= 1/α on the whole box
    assert density.mean() == pytest.approx(1.0, abs=0.02)  # ∫ q = E_p[q / p] = 1
    drawn, _ = q.sample(np.random.default_rng(1), 100_000)
    assert np.exp(-q.log_q(drawn)).mean() == pytest.approx(1.0, abs=0.02)  # E_q[p / q] = 1


def test_a_beta_keeps_the_moments_it_is_made_from():
    g = BetaProduct(np.array([0.3, 0.5]), np.array([0.1, 1 / np.sqrt(12)]))
    mean, sd = g.moments()
    np.testing.assert_allclose(mean, [0.3, 0.5])
    np.testing.assert_allclose(sd, [0.1, 1 / np.sqrt(12)])
    np.testing.assert_allclose(g.shapes[0][1], 1.0)  # the uniform is Beta(1, 1)


def test_the_elite_is_the_collisions_or_the_most_critical_share():
    f = np.r_[np.zeros(3), np.linspace(0.1, 1.0, 27)]
    assert elite(f, f == 0, rho=0.1).tolist() == (f == 0).tolist()  # 3 >= 10 % of 30
    one = np.r_[0.0, np.linspace(0.1, 1.0, 29)]
    top = elite(one, one == 0, rho=0.2)
    assert top.sum() == 6 and top[:6].all()  # too few collisions: the top 20 %
    one[1] = np.nan
    assert not elite(one, one == 0, rho=0.2)[1]  # an unknown outcome is never elite


def test_the_update_narrows_only_the_dimensions_the_failures_depend_on():
    rng = np.random.default_rng(3)
    u = rng.uniform(size=(400, 4))
    f = criticality(TOY, TOY.denormalise(u))  # 4 % collide: the elite is the top 10 %
    q = ce_update(DefensiveMixture(ALPHA), u, np.zeros(400), f, f == 0, smoothing=1.0)
    mean, sd = q.proposal.moments()
    assert mean[0] > 0.75 and mean[1] < 0.25 and (sd[:2] < 0.15).all()
    np.testing.assert_allclose(mean[2:], 0.5)  # p's marginal kept
    np.testing.assert_allclose(sd[2:], 1 / np.sqrt(12))


def test_every_proposal_carries_its_exact_densities_and_a_resume_recomputes_them():
    strategy, records, props = acquire("ce-is", TOY, seed=4, n=100)
    log_p = -np.log(TOY.high - TOY.low).sum()
    assert all(p.log_p == pytest.approx(log_p) for p in props)
    ratio = records.importance_ratio()
    assert (ratio[:40] == 1).all() and (ratio[40:60] == pytest.approx(1.0))  # batch 0: p
    assert ratio.max() <= 1 / ALPHA + 1e-9 and ratio[60:].min() < 0.5  # later: adapted
    resumed = make_strategy("ce-is", TOY, seed=4)
    resumed.replay(records.params[40:], records.fitness[40:])
    log_q, again_p = resumed.log_densities(records, 40)
    assert np.isnan(log_q[:40]).all()
    np.testing.assert_array_equal(log_q[40:], records.log_q[40:])
    np.testing.assert_array_equal(again_p[40:], records.log_p[40:])


def test_it_finds_more_failures_than_uniform_and_its_weighted_rate_is_p_s():
    found, rates, uniform = [], [], []
    for seed in range(6):
        _, records, _ = acquire("ce-is", TOY, seed, n=160)
        hit = records.collided[40:]
        found.append(hit.sum())
        rates.append((hit * records.importance_ratio()[40:]).mean())
        uniform.append(acquire("uniform", TOY, seed, n=160)[1].collided[40:].sum())
    assert np.mean(found) > 3 * np.mean(uniform)  # uniform: 4 % of 160 ≈ 6.4
    assert np.mean(rates) == pytest.approx(0.04, abs=0.015)  # unbiased: E[w·y] = P_p(fail)


def test_pool_mode_draws_unused_rows_with_their_densities():
    pool = TOY.sample(np.random.default_rng(8), 600)
    strategy = make_strategy("ce-is", TOY, seed=2, pool=pool)
    init = pool[:40]
    f = criticality(TOY, init)
    records = Records(init, np.full(40, np.nan), fitness=f, collided=f == 0)
    rows = []
    for _ in range(60):
        prop = strategy.propose(records)
        rows.append(prop.pool_index)
        np.testing.assert_array_equal(prop.x, pool[prop.pool_index])
        f = float(criticality(TOY, prop.x))
        strategy.tell(prop.x, f)
        records = records.append(prop.x, fitness=f, collided=f == 0, log_q=prop.log_q,
                                 log_p=prop.log_p)
    assert len(set(rows)) == 60 and min(rows) >= 40
    assert np.isfinite(records.log_q[40:]).all()


def test_a_lower_screening_z_lets_a_weaker_departure_adapt():
    rng = np.random.default_rng(5)
    u = rng.uniform(size=(200, 2))
    u[:20, 0] = 0.25 + 0.75 * (np.arange(20) + 0.5) / 20  # the elite leans high, mean 0.625
    f = np.where(np.arange(200) < 20, 0.1, 0.9)  # the elite: the 20 most critical runs
    strict = ce_update(DefensiveMixture(ALPHA), u, np.zeros(200), f, f == 0, smoothing=1.0,
                       screen_z=3.0, rho=0.1)
    loose = ce_update(DefensiveMixture(ALPHA), u, np.zeros(200), f, f == 0, smoothing=1.0,
                      screen_z=1.0, rho=0.1)
    assert strict.proposal.moments()[0][0] == pytest.approx(0.5)  # screened out at z = 3
    assert loose.proposal.moments()[0][0] > 0.6  # adapts at z = 1


@pytest.mark.parametrize("option", [{"alpha": 0.0}, {"rho": 1.0}, {"batch": 0},
                                    {"screen_z": -1.0}])
def test_bad_options_are_named(option):
    with pytest.raises(StrategyError, match=next(iter(option))):
        make_strategy("ce-is", HIGHWAY, seed=0, **option)
