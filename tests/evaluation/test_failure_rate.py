"""The failure-rate estimates: unbiased under a proposal concentrated on the failures, with an
interval that covers, and a smaller error than plain Monte Carlo at the same budget."""

import numpy as np
import pytest

from evoeye.evaluation.failure_rate import failure_rate
from evoeye.evolve.search.cross_entropy import BetaProduct, DefensiveMixture

TRUTH = 0.05 * 0.1  # p-mass of the failure region u0 > 0.95, u1 > 0.9 of the unit cube
PROPOSAL = DefensiveMixture(0.2, BetaProduct(np.array([0.96, 0.93, 0.5]),
                                             np.array([0.03, 0.05, 1 / np.sqrt(12)])))
RUNS, REPEATS = 200, 400


def fails(u):
    return (u[:, 0] > 0.95) & (u[:, 1] > 0.9)


def repeated(method):
    """(IS estimates, their intervals' coverage of the truth, plain MC estimates) over seeds."""
    est, covered, plain = [], [], []
    for seed in range(REPEATS):
        u, _ = PROPOSAL.sample(np.random.default_rng([seed, 1]), RUNS)
        r = failure_rate(fails(u), np.exp(-PROPOSAL.log_q(u)), method)
        est.append(r.value)
        covered.append(r.low <= TRUTH <= r.high)
        v = np.random.default_rng([seed, 2]).uniform(size=(RUNS, 3))
        plain.append(failure_rate(fails(v), np.ones(RUNS)).value)
    return np.array(est), np.array(covered), np.array(plain)


@pytest.mark.parametrize("method", ["is", "self-normalised"])
def test_the_estimate_is_unbiased_covers_and_beats_plain_monte_carlo(method):
    est, covered, plain = repeated(method)
    assert abs(est.mean() - TRUTH) < 3 * est.std() / np.sqrt(REPEATS)
    assert 0.9 <= covered.mean() <= 0.99
    rel = np.sqrt(((est - TRUTH) ** 2).mean()) / TRUTH
    rel_plain = np.sqrt(((plain - TRUTH) ** 2).mean()) / TRUTH  # ≈ √((1 − P)/(nP)) ≈ 1
    assert rel < rel_plain / 3


def test_plain_monte_carlo_is_the_share_that_collided_and_its_relative_error():
    r = failure_rate([True] * 5 + [False] * 95, np.ones(100))
    assert r.value == pytest.approx(0.05) and r.effective_runs == pytest.approx(100)
    assert r.relative_error == pytest.approx(np.sqrt(0.05 * 0.95 * 100 / 99 / 100) / 0.05)
    assert failure_rate([True] * 5 + [False] * 95, np.ones(100), "self-normalised").value == \
        pytest.approx(0.05)


def test_no_collision_gives_zero_with_a_rule_of_three_bound():
    r = failure_rate([False] * 300, np.full(300, 2.0))
    assert r.value == 0 and r.relative_error is None
    assert r.high == pytest.approx(-np.log(0.05) * 2.0 / 300)


@pytest.mark.parametrize(("outcomes", "weights", "words"), [
    ([True, False], [1.0], "one weight per run"),
    ([True, False], [1.0, 0.0], "finite and > 0"),
    ([True, False], [1.0, np.nan], "finite and > 0"),
])
def test_bad_weights_are_named(outcomes, weights, words):
    with pytest.raises(ValueError, match=words):
        failure_rate(outcomes, weights)


def test_an_unknown_estimator_is_named():
    with pytest.raises(ValueError, match="unknown failure-rate estimator 'naive'"):
        failure_rate([True], [1.0], "naive")
