"""Statistics over seeds against scipy and known answers, on seeded synthetic data.

Repetition tests (false-positive rate, coverage, power) use a fixed seed, so they cannot flake;
their bounds are still wide enough (≥ 4 binomial standard errors) that any seed would pass if
the code is right, and narrow enough that a test claiming differences it does not see, or an
interval that is too short, fails.
"""

from __future__ import annotations

import math
import statistics

import numpy as np
import pytest
from scipy import stats

from evoeye.evaluation.stats import (
    compare_paired,
    finite_mean,
    mean_ci,
    median_ci,
    minimum_detectable_effect,
    paired_power,
    paired_warnings_p,
    pairs_needed,
    proportion_ci,
    rate_ci,
    sample_sd,
    sd_of_differences,
)


def test_sample_sd_is_ddof_1_and_skips_undefined_values() -> None:
    values = [0.2, 0.5, 0.3]
    assert sample_sd(values) == pytest.approx(statistics.stdev(values))
    assert sample_sd(values) == pytest.approx(math.sqrt(3 / 2) * np.std(values))  # 1.22× at n=3
    assert sample_sd([0.2, np.nan, 0.5, 0.3]) == pytest.approx(statistics.stdev(values))
    assert sample_sd([0.4]) is None and sample_sd([]) is None
    assert sample_sd([0.1] * 6) == 0.0 and mean_ci([0.1] * 6).low == mean_ci([0.1] * 6).high


def test_finite_mean_skips_undefined_values_and_is_none_without_any() -> None:
    import warnings

    assert finite_mean([0.2, np.nan, 0.5, np.inf, 0.3]) == pytest.approx(1.0 / 3)
    assert finite_mean([0.2, np.nan, 0.5]) == mean_ci([0.2, np.nan, 0.5]).mean
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no 'Mean of empty slice'
        assert finite_mean([np.nan, np.nan]) is None and finite_mean([]) is None


def test_mean_ci_is_the_t_interval() -> None:
    ci = mean_ci([1, 2, 3, 4, 5])  # mean 3, SD √2.5, t(0.975, 4) = 2.776445
    half = 2.7764451051977987 * math.sqrt(2.5) / math.sqrt(5)
    assert (ci.n, ci.mean, ci.sd) == (5, 3.0, pytest.approx(math.sqrt(2.5)))
    assert (ci.low, ci.high) == pytest.approx((3 - half, 3 + half))
    ref = stats.ttest_1samp([1, 2, 3, 4, 5], 0).confidence_interval(0.9)
    assert (mean_ci([1, 2, 3, 4, 5], 0.9).low, mean_ci([1, 2, 3, 4, 5], 0.9).high) == \
        pytest.approx((ref.low, ref.high))
    assert mean_ci([0.7]).low is None and mean_ci([]).mean is None
    with pytest.raises(ValueError, match="confidence"):
        mean_ci([1, 2], 95)


def test_mean_ci_covers_the_true_mean_about_95_percent_of_the_time() -> None:
    rng = np.random.default_rng(3)
    cover = [(c.low <= 0.3 <= c.high) for c in (mean_ci(rng.normal(0.3, 0.1, 5))
                                                 for _ in range(2000))]
    assert 0.93 <= np.mean(cover) <= 0.97  # SE 0.005


def _null_pairs(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Two correlated methods with the same mean F1 (0.5) on n seeds."""
    a = rng.normal(0.5, 0.1, n)
    return a, 0.6 * a + rng.normal(0.2, 0.08, n)


def test_no_true_difference_is_claimed_at_about_the_nominal_rate() -> None:
    rng = np.random.default_rng(11)
    out = [compare_paired(*_null_pairs(rng, 20), n_resamples=999, seed=i) for i in range(1000)]
    false_positive = np.mean([c.p_value < 0.05 for c in out])
    assert 0.02 <= false_positive <= 0.08  # α = 0.05, SE 0.007
    coverage = np.mean([c.ci_low <= 0.0 <= c.ci_high for c in out])
    assert 0.88 <= coverage <= 0.99  # a 95 % BCa interval of 20 pairs
    assert {c.ci_method for c in out} == {"BCa"}


def test_a_large_true_difference_is_found() -> None:
    rng = np.random.default_rng(5)
    a, b = _null_pairs(rng, 20)
    c = compare_paired(a + 0.1, b)  # 0.1 F1 better, differences' SD ≈ 0.08
    assert c.p_value < 1e-4 and c.ci_low > 0.0
    assert c.ci_low < 0.1 < c.ci_high
    assert c.mean_diff == pytest.approx(np.mean(a + 0.1 - b))
    assert c.sd_diff == pytest.approx(np.std(a + 0.1 - b, ddof=1))
    assert c.correlation == pytest.approx(stats.pearsonr(a, b).statistic)
    assert c.p_value == pytest.approx(stats.wilcoxon(a + 0.1, b, method="exact").pvalue)


def test_the_paired_comparison_is_reproducible_and_drops_incomplete_pairs() -> None:
    rng = np.random.default_rng(6)
    a, b = _null_pairs(rng, 12)
    assert compare_paired(a, b, seed=4) == compare_paired(a, b, seed=4)
    a_nan = np.append(a, np.nan)
    assert compare_paired(a_nan, np.append(b, 0.3), seed=4) == compare_paired(a, b, seed=4)
    with pytest.raises(ValueError, match="one of each per seed"):
        compare_paired(a, b[:-1])


def test_zero_differences_and_tiny_samples() -> None:
    same = compare_paired([0.2, 0.4, 0.6], [0.2, 0.4, 0.6])
    assert same.p_value == 1.0 and same.zeros == 3 and same.min_p is None
    assert (same.ci_low, same.ci_high, same.ci_method) == (0.0, 0.0, "degenerate")
    # three seeds all better: the best a two-sided signed-rank test can say is p = 2/2³
    three = compare_paired([0.5, 0.6, 0.7], [0.3, 0.35, 0.45])
    assert three.p_value == pytest.approx(0.25) and three.min_p == pytest.approx(0.25)
    # zeros are left out of the test and counted
    z = compare_paired([0.5, 0.6, 0.7, 0.4, 0.9, 0.8, 0.75],
                       [0.5, 0.6, 0.3, 0.1, 0.2, 0.35, 0.5])
    assert z.zeros == 2 and z.min_p == pytest.approx(2 / 2**5) and z.p_value == pytest.approx(
        stats.wilcoxon([0.4, 0.3, 0.7, 0.45, 0.25], method="exact").pvalue)
    one = compare_paired([0.5], [0.3])
    assert one.n == 1 and one.ci_low is None and one.p_value == 1.0
    assert compare_paired([], []).n == 0


def test_tied_differences_use_the_permutation_distribution() -> None:
    # differences 0.1 (×6) and -0.1 (×2): every |difference| ties; 2·P(≤ 2 of 8 negative)
    c = compare_paired([0.6] * 6 + [0.4] * 2, [0.5] * 8)
    exact = 2 * stats.binom.cdf(2, 8, 0.5)
    assert c.p_value == pytest.approx(exact)  # 2^8 sign flips, enumerated


def test_sd_of_differences_from_the_pair_correlation() -> None:
    assert sd_of_differences(3.0, 4.0, 0.0) == pytest.approx(5.0)
    assert sd_of_differences(2.0, 2.0, 1.0) == 0.0
    assert sd_of_differences(8.5, 8.5, 0.5) == pytest.approx(8.5)
    with pytest.raises(ValueError, match="correlation"):
        sd_of_differences(1.0, 1.0, 1.5)


@pytest.mark.parametrize(("effect", "pairs"), [(0.3, 90), (0.5, 34), (0.8, 15), (1.0, 10)])
def test_pairs_needed_for_the_paired_t_test_match_published_tables(effect, pairs) -> None:
    # G*Power 3.1, "t tests – means: difference between two dependent means", two-sided α 0.05,
    # power 0.8, effect size d_z: 90, 34, 15 and 10 pairs
    assert pairs_needed(effect, 1.0, 1.0, 0.5, test="t") == pairs  # SD(a − b) = 1
    assert paired_power(pairs, effect, 1.0, test="t") >= 0.8
    assert paired_power(pairs - 1, effect, 1.0, test="t") < 0.8


def test_t_power_matches_the_rejection_rate_of_scipys_paired_t_test() -> None:
    rng = np.random.default_rng(8)
    n, diff, sd = 12, 0.06, 0.1
    a = rng.normal(0.5, 0.1, (4000, n))
    b = a - diff + rng.normal(0.0, sd, (4000, n))
    rejected = stats.ttest_rel(a, b, axis=1).pvalue < 0.05
    assert np.mean(rejected) == pytest.approx(paired_power(n, diff, sd, test="t"), abs=0.03)


def test_the_wilcoxon_design_has_the_power_it_promises() -> None:
    sd_a = sd_b = 0.085  # the S1 Hard Set's SD, 8.5 F1 points, and a 5-point difference
    n = pairs_needed(0.05, sd_a, sd_b, 0.6)
    assert 16 <= n <= 25 and n > pairs_needed(0.05, sd_a, sd_b, 0.6, test="t")
    rng = np.random.default_rng(9)
    cov = [[sd_a**2, 0.6 * sd_a * sd_b], [0.6 * sd_a * sd_b, sd_b**2]]
    found = []
    for i in range(600):
        ab = rng.multivariate_normal([0.55, 0.50], cov, n)
        found.append(compare_paired(ab[:, 0], ab[:, 1], n_resamples=99, seed=i).p_value < 0.05)
    assert 0.73 <= np.mean(found) <= 0.9  # target 0.8, SE 0.016


def test_too_few_pairs_have_no_wilcoxon_power() -> None:
    sd = sd_of_differences(0.085, 0.085, 0.5)
    assert paired_power(5, 0.05, sd) == 0.0  # p ≥ 2/2⁵ = 0.0625 whatever the data
    assert paired_power(5, 0.05, sd, alpha=0.1) > 0.0
    assert 0.0 < paired_power(6, 0.05, sd) < paired_power(7, 0.05, sd)
    assert 0.0 < paired_power(3, 0.05, sd, test="t") < 0.11  # the t-test: 10 %


def test_power_inputs_are_checked() -> None:
    with pytest.raises(ValueError, match="non-zero difference"):
        pairs_needed(0.0, 1.0, 1.0, 0.5)
    with pytest.raises(ValueError, match="test must be"):
        paired_power(10, 0.5, 1.0, test="welch")
    with pytest.raises(ValueError, match="pairs"):
        paired_power(1, 0.5, 1.0)
    # identical noise: differences are exact, and the smallest design that can reject decides
    assert pairs_needed(0.05, 0.1, 0.1, 1.0, test="t") == 2
    assert pairs_needed(0.05, 0.1, 0.1, 1.0) == 6  # Wilcoxon: 2/2⁵ > 0.05 ≥ 2/2⁶
    assert pairs_needed(0.05, 0.1, 0.1, 1.0, alpha=0.01) == 8  # 2/2⁷ > 0.01 ≥ 2/2⁸
    assert paired_power(6, 0.05, 1e-9) > 0.99 and paired_power(5, 0.05, 1e-9) == 0.0


def test_designs_of_thousands_of_pairs_are_sized_not_overflowed() -> None:
    # a noisy share (SD 0.7, e.g. 0/1 outcomes of one-run campaigns) needs ≈ 2 (z_α + z_β)² σ²/δ²
    # ≈ 3,000 pairs to detect 5 points: past 1,023, where 2.0 ** n overflows a float
    sd = sd_of_differences(0.7, 0.7, 0.0)
    n = pairs_needed(0.05, 0.7, 0.7, 0.0)
    t_n = 2 * (stats.norm.ppf(0.975) + stats.norm.ppf(0.8)) ** 2 * 0.7**2 / 0.05**2
    assert 0.95 * t_n / 0.955 < n < 1.1 * t_n / 0.955  # the Wilcoxon ARE, 3/π
    assert paired_power(n, 0.05, sd) >= 0.8 > paired_power(n - 1, 0.05, sd)
    with pytest.raises(ValueError, match="more than 1000 pairs"):
        pairs_needed(0.05, 0.7, 0.7, 0.0, max_pairs=1000)
    big = compare_paired(np.arange(1, 1201) / 1e3, np.zeros(1200))
    assert big.min_p == 0.0 and big.p_value < 1e-100  # 2 / 2^1200 underflows to 0, no error


def test_a_share_of_runs_has_the_wilson_interval_even_at_none_or_all() -> None:
    e = proportion_ci(6, 8)
    assert (e.value, e.n, e.method) == (0.75, 8, "wilson")
    z = stats.norm.ppf(0.975)  # Wilson's formula by hand
    centre = (0.75 + z**2 / 16) / (1 + z**2 / 8)
    half = z / (1 + z**2 / 8) * math.sqrt(0.75 * 0.25 / 8 + z**2 / 256)
    assert (e.low, e.high) == pytest.approx((centre - half, centre + half))
    none, every = proportion_ci(0, 2), proportion_ci(2, 2)
    assert none.low == 0.0 and none.high > 0.5 and every.high == 1.0 and every.low < 0.5
    assert proportion_ci(0, 0).value is None


def test_a_rate_over_runs_resamples_runs_and_bounds_a_zero_count() -> None:
    rng = np.random.default_rng(3)
    events, hours = rng.poisson(2.0, 40), rng.uniform(0.01, 0.02, 40)
    e = rate_ci(events, hours)
    assert e.value == pytest.approx(events.sum() / hours.sum()) and e.method == "bootstrap"
    assert e.low < e.value < e.high
    bursty = rate_ci(np.r_[np.zeros(39), events.sum()], hours)  # the same count in one run
    assert bursty.value == pytest.approx(e.value) and bursty.high - bursty.low > 2 * (
        e.high - e.low)  # runs are the unit: one bursty run is far less sure
    zero = rate_ci(np.zeros(5), np.full(5, 0.5))
    assert (zero.value, zero.low) == (0.0, 0.0)
    assert zero.high == pytest.approx(-math.log(0.05) / 2.5) and zero.method == "poisson-zero"
    assert rate_ci([], []).value is None
    with pytest.raises(ValueError, match="one exposure per run"):
        rate_ci([1, 2], [0.1])


def test_a_median_over_runs_has_a_bootstrap_interval_from_two_runs_on() -> None:
    e = median_ci([1.0, 2.0, 3.0, 4.0, 10.0])
    assert e.value == 3.0 and 1.0 <= e.low <= 3.0 <= e.high <= 10.0
    one = median_ci([2.5])
    assert (one.value, one.low, one.high, one.n) == (2.5, None, None, 1)
    assert median_ci([]).value is None
    assert median_ci([1.0, 2.0, 3.0]) == median_ci([1.0, 2.0, 3.0])  # seeded


def test_paired_warnings_compare_only_the_runs_one_monitor_alone_warned_of() -> None:
    a = [True] * 12 + [False] * 3
    b = [False] * 10 + [True] * 2 + [False] * 3
    assert paired_warnings_p(a, b) == pytest.approx(stats.binomtest(10, 10).pvalue)  # 0.002
    assert paired_warnings_p(a, a) == 1.0
    assert paired_warnings_p([True, False], [False, True]) == 1.0
    with pytest.raises(ValueError, match="one flag each"):
        paired_warnings_p([True], [True, False])


@pytest.mark.parametrize(("effect", "pairs"), [(0.3, 90), (0.5, 34), (0.8, 15), (1.0, 10)])
def test_the_minimum_detectable_effect_inverts_the_published_tables(effect, pairs) -> None:
    # the G*Power designs above: `pairs` pairs detect d_z = effect, one pair fewer does not
    assert minimum_detectable_effect(pairs, 1.0) <= effect < minimum_detectable_effect(
        pairs - 1, 1.0)
    mde = minimum_detectable_effect(pairs, 2.0)  # in the SD's units
    assert paired_power(pairs, mde, 2.0, test="t") == pytest.approx(0.8, abs=1e-6)


def test_the_minimum_detectable_effect_is_the_normal_formula_at_many_pairs() -> None:
    # (z_0.975 + z_0.8) · SD / √n = (1.95996 + 0.84162) · 2 / 100 = 0.056032
    assert minimum_detectable_effect(10_000, 2.0) == pytest.approx(0.056032, rel=1e-3)
    assert minimum_detectable_effect(40, 2.0) < minimum_detectable_effect(10, 2.0)
    assert minimum_detectable_effect(10, 0.0) == 0.0


def test_no_effect_is_detectable_below_the_wilcoxon_floor() -> None:
    assert math.isinf(minimum_detectable_effect(5, 1.0, test="wilcoxon"))
    assert minimum_detectable_effect(10, 1.0, test="wilcoxon") > minimum_detectable_effect(10, 1.0)
    with pytest.raises(ValueError, match="power"):
        minimum_detectable_effect(10, 1.0, power=1.0)
