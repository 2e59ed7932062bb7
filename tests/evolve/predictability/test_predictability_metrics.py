"""The predictability figures on synthetic data whose answer is known."""

import numpy as np
import pytest

from evoeye.evolve.predictability import metrics
from evoeye.evolve.predictability.check import (
    RegimeRuns,
    boundary_pick,
    label_noise,
    uniform_pick,
)
from evoeye.scenarios import get_scenario

CROSSING = get_scenario("unprotected-intersection")


def _u(n=300, seed=0):
    return np.random.default_rng(seed).uniform(size=(n, CROSSING.dim))


def test_a_planted_boundary_is_predicted_and_noise_is_not():
    u = _u()
    planted = metrics.cv_auroc(u, u[:, 0] + u[:, 1] < 0.8, seed=0)
    assert planted.auroc > 0.9 and planted.runs == 300
    noise = metrics.cv_auroc(u, np.random.default_rng(1).random(300) < 0.3, seed=0)
    assert abs(noise.auroc - 0.5) < 0.1


def test_the_auroc_comes_with_its_interval_and_each_folds():
    u = _u()
    planted = metrics.cv_auroc(u, u[:, 0] + u[:, 1] < 0.8, seed=0)
    low, high = planted.auroc_ci
    assert 0.8 < low < planted.auroc < high <= 1.0
    assert len(planted.fold_aurocs) == metrics.FOLDS and min(planted.fold_aurocs) > 0.8
    noise = metrics.cv_auroc(u, np.random.default_rng(1).random(300) < 0.3, seed=0)
    assert noise.auroc_ci[0] < 0.5 < noise.auroc_ci[1]
    assert min(noise.fold_aurocs) < noise.auroc < max(noise.fold_aurocs)


def test_too_few_of_one_class_gives_no_auroc():
    u = _u(40)
    y = np.zeros(40, bool)
    y[:3] = True  # fewer than one per fold
    assert metrics.cv_auroc(u, y, seed=0).auroc is None


def test_a_value_that_depends_on_theta_is_predictive_and_noise_is_not():
    u, rng = _u(), np.random.default_rng(2)
    smooth = metrics.cv_regression(u, u[:, 2] + 0.1 * rng.normal(size=300), seed=0)
    assert smooth.predictive and smooth.spearman > 0.8 and smooth.r2 > 0.6
    noise = metrics.cv_regression(u, rng.normal(size=300), seed=0)
    assert not noise.predictive and noise.r2 < 0.05


def test_non_finite_values_are_left_out():
    u = _u(100)
    y = u[:, 0].copy()
    y[::4] = np.nan
    assert metrics.cv_regression(u, y, seed=0).runs == 75


def _runs(n=40):
    params = CROSSING.denormalise(_u(n, seed=3))
    u = CROSSING.normalise(params)
    return RegimeRuns(CROSSING.name, "default", None, np.arange(n).astype(str).astype(object),
                      params, u[:, 0] < 0.5, np.zeros(n), np.zeros(n, object))


def test_a_deterministic_outcome_never_flips():
    runs = _runs()

    def deterministic(scenario, x, seed, profile):
        assert profile == "default" and scenario == CROSSING.name
        return float(CROSSING.normalise(x)[0] < 0.5)

    f = label_noise(runs, uniform_pick(40, 20, 0), seeds=3, simulate=deterministic)
    assert (f.thetas, f.seeds) == (20, 3)
    assert f.flip_share == 0.0 and f.ambiguous_share == 0.0


def test_a_coin_flip_outcome_flips_half_the_time_and_seeds_are_new_and_distinct():
    runs = _runs()
    used = []

    def coin(scenario, x, seed, profile):
        used.append(seed)
        return float(np.random.default_rng(seed).random() < 0.5)

    f = label_noise(runs, np.arange(40), seeds=5, simulate=coin)
    assert 0.4 < f.flip_share < 0.6 and f.ambiguous_share > 0.9
    assert len(set(used)) == 200


def test_the_boundary_sample_is_where_collision_is_a_coin_toss():
    p = np.array([0.9, 0.45, 0.1, 0.62, 0.5, 0.0])
    np.testing.assert_array_equal(boundary_pick(p, 3), [1, 3, 4])
    picked = uniform_pick(40, 10, seed=0)
    assert len(set(picked)) == 10 and list(picked) == sorted(picked)


def test_failed_re_simulations_are_left_out():
    f = metrics.flips(np.array([True, False]), np.array([[1.0, np.nan], [np.nan, 1.0]]))
    assert f.flip_share == 0.5 and f.ambiguous_share == 0.5 and f.collision_share == 1.0
    with pytest.raises(ValueError, match=r"\(n, k\)"):
        metrics.flips(np.array([True]), np.array([1.0]))


def test_the_verdict_says_plainly_when_theta_cannot_steer():
    no_error = metrics.Regressed(200, -0.1, 0.02, 0.7)
    lines = metrics.verdict(metrics.Classified(200, 50, 0.85), no_error, None)
    assert "learnable" in lines[0]
    assert "no strategy that chooses θ can beat Uniform" in lines[1]
    good = metrics.verdict(metrics.Classified(200, 50, 0.52), metrics.Regressed(
        200, 0.2, 0.45, 1e-9), metrics.Flips(30, 4, 0.0, 0.0, 0.3),
        metrics.Flips(30, 4, 0.1, 0.2, 0.3))
    assert "hardly predicts" in good[0] and "can steer" in good[1]
    assert "0 % of the outcomes of θ drawn uniformly" in good[2] and "function of θ" in good[2]
    assert "10 % of the outcomes of the θ nearest the failure boundary" in good[3]
    assert "chance" in good[3]


def test_a_significant_rank_that_explains_little_of_the_error_is_called_weak():
    weak = metrics.Regressed(400, 0.04, 0.27, 1e-7)
    assert weak.predictive
    line = metrics.verdict(metrics.Classified(400, 100, 0.82), weak)[1]
    assert "only weakly" in line and "R² 0.04" in line and "can gain little" in line
    strong = metrics.verdict(metrics.Classified(400, 100, 0.82),
                             metrics.Regressed(400, metrics.R2_MIN, 0.5, 1e-9))[1]
    assert "only weakly" not in strong and "can steer toward" in strong
