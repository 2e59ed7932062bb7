"""How sure a figure is: over seeds (sample SDs, intervals, paired tests, power) and over runs
(the intervals of a report's headline, at the end of the module; docs/reports.md).

Every method of an experiment runs on the same campaign seeds, so two methods are compared pair
by pair (seed by seed). The choices, and why:

* Spread: the sample SD (ddof = 1). The population SD (ddof = 0) understates it by
  √(n / (n − 1)), 1.22× at n = 3.
* The mean over seeds of one method: Student's t interval (`scipy.stats.t`), exact for normal
  values and the usual choice at the handful of seeds one method has.
* The mean paired difference: a bootstrap CI (`scipy.stats.bootstrap`, seeded) of the mean of
  the differences, resampling whole pairs. BCa rather than percentile: it corrects the
  bootstrap distribution's bias and skew (second-order accurate; Efron 1987), which matters for
  differences of bounded rates (F1 near 0 or 1) at the 16–25 pairs the design needs; the
  percentile interval is first-order only and covers less at that size. Where BCa is undefined
  (its jackknife acceleration is 0/0, e.g. all but one difference equal) the percentile interval
  stands in and `ci_method` says so; all differences equal give the point itself.
* The paired test: Wilcoxon signed-rank, two-sided (`scipy.stats.wilcoxon`), free of the
  normality a paired t-test needs. Zero differences are dropped ("wilcox": a pair that did not
  differ says nothing about the direction) and counted in `zeros`; none left gives p = 1. The
  p-value is exact for ≤ 50 distinct non-zero differences; with tied differences it comes from
  the sign-flip permutation distribution of the signed ranks (exact enumeration up to 13 pairs,
  else 9999 seeded flips), above 50 from the normal approximation. With m non-zero differences no
  two-sided p can fall below 2 / 2^m (`min_p`): 5 pairs can never reach p < 0.05.
* Power and sample size: the paired t-test's power from the noncentral t (`scipy.stats.nct`),
  standardised effect d / SD(a − b) with SD(a − b)² = SD_a² + SD_b² − 2ρ·SD_a·SD_b for the
  measured pair correlation ρ. The Wilcoxon test's power uses its asymptotic relative efficiency
  to the t-test, 3/π for normal differences (Lehmann; G*Power's A.R.E. method): n pairs for the
  Wilcoxon count as 3n/π for the t-test. That is asymptotic; below it, the floor on p rules: with
  2 / 2^n > α the test can never reject, and its power is 0. The minimum detectable effect is
  that power inverted: the true difference found with the asked power at the pairs run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
from scipy import optimize, stats

CONFIDENCE = 0.95
N_RESAMPLES = 9999
WILCOXON_ARE = 3.0 / math.pi  # Wilcoxon signed-rank vs t-test, normal differences
EXACT_MAX_PAIRS = 50  # scipy's own bound for the exact signed-rank distribution
POWER_TESTS = ("wilcoxon", "t")


def _finite(values: Sequence[float] | np.ndarray) -> np.ndarray:
    a = np.asarray(values, dtype=float).reshape(-1)
    return a[np.isfinite(a)]


def finite_mean(values: Sequence[float] | np.ndarray) -> float | None:
    """The mean of the finite values (NaN, e.g. an undefined seed, left out); None for none."""
    a = _finite(values)
    return float(a.mean()) if len(a) else None


def sample_sd(values: Sequence[float] | np.ndarray) -> float | None:
    """Sample SD (ddof = 1) of the finite values; None for fewer than two; exactly 0 when they
    are all equal (np.std's rounding would leave ~1e-17 of a mean that is not exactly theirs)."""
    a = _finite(values)
    if len(a) < 2:
        return None
    return 0.0 if np.ptp(a) == 0 else float(np.std(a, ddof=1))


@dataclass(frozen=True)
class MeanCI:
    """A mean over seeds with its sample SD and Student-t confidence interval (None: n < 2)."""

    n: int
    mean: float | None
    sd: float | None
    low: float | None
    high: float | None
    confidence: float = CONFIDENCE

    def to_dict(self) -> dict:
        return asdict(self)


def mean_ci(values: Sequence[float] | np.ndarray, confidence: float = CONFIDENCE) -> MeanCI:
    """The mean of the finite values and its t interval (NaN, e.g. undefined seeds, left out)."""
    _check_confidence(confidence)
    a = _finite(values)
    if len(a) == 0:
        return MeanCI(0, None, None, None, None, confidence)
    mean, sd = float(a.mean()), sample_sd(a)
    if sd is None:
        return MeanCI(1, mean, None, None, None, confidence)
    half = float(stats.t.ppf(0.5 + confidence / 2, len(a) - 1)) * sd / math.sqrt(len(a))
    return MeanCI(len(a), mean, sd, mean - half, mean + half, confidence)


@dataclass(frozen=True)
class PairedComparison:
    """Method a against method b over the seeds both have a finite value for."""

    n: int  # pairs
    mean_a: float | None
    mean_b: float | None
    sd_a: float | None
    sd_b: float | None
    correlation: float | None  # Pearson ρ of a and b over the pairs (None if undefined)
    mean_diff: float | None  # mean of a − b
    sd_diff: float | None
    ci_low: float | None  # bootstrap CI of mean_diff (None: n < 2)
    ci_high: float | None
    ci_method: str | None  # "BCa", "percentile" or "degenerate" (all differences equal)
    p_value: float | None  # two-sided Wilcoxon signed-rank (None: no pairs)
    zeros: int  # pairs with a − b = 0, left out of the test
    min_p: float | None  # the smallest p the test can give with these pairs
    confidence: float = CONFIDENCE

    def to_dict(self) -> dict:
        return asdict(self)


def compare_paired(a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray, *,
                   confidence: float = CONFIDENCE, n_resamples: int = N_RESAMPLES,
                   seed: int = 0) -> PairedComparison:
    """Mean paired difference a − b with its bootstrap CI, the Wilcoxon signed-rank p and the
    sample SDs (module doc); a[i] and b[i] come from the same seed, pairs with a non-finite
    side are left out. The same inputs and seed give the same result."""
    _check_confidence(confidence)
    a, b = np.asarray(a, dtype=float).reshape(-1), np.asarray(b, dtype=float).reshape(-1)
    if a.shape != b.shape:
        raise ValueError(f"paired values need one of each per seed: {len(a)} against {len(b)}")
    keep = np.isfinite(a) & np.isfinite(b)
    a, b = a[keep], b[keep]
    d = a - b
    n = len(d)
    if n == 0:
        return PairedComparison(0, None, None, None, None, None, None, None, None, None, None,
                                None, 0, None, confidence)
    low, high, method = _bootstrap_ci(d, confidence, n_resamples, seed)
    p, zeros, min_p = _wilcoxon(d, n_resamples, seed)
    return PairedComparison(n, float(a.mean()), float(b.mean()), sample_sd(a), sample_sd(b),
                            _correlation(a, b), float(d.mean()), sample_sd(d), low, high,
                            method, p, zeros, min_p, confidence)


def _check_confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")


def _correlation(a: np.ndarray, b: np.ndarray) -> float | None:
    if len(a) < 2 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return None
    return float(stats.pearsonr(a, b).statistic)


def _bootstrap_ci(d: np.ndarray, confidence: float, n_resamples: int, seed: int
                  ) -> tuple[float | None, float | None, str | None]:
    if len(d) < 2:
        return None, None, None
    if np.ptp(d) == 0:
        return float(d[0]), float(d[0]), "degenerate"
    for method in ("BCa", "percentile"):
        with np.errstate(invalid="ignore", divide="ignore"):
            ci = stats.bootstrap((d,), np.mean, confidence_level=confidence,
                                 n_resamples=n_resamples, method=method,
                                 rng=np.random.default_rng(seed)).confidence_interval
        if np.isfinite(ci.low) and np.isfinite(ci.high):
            return float(ci.low), float(ci.high), method
    raise RuntimeError("bootstrap gave no finite interval")  # unreachable for ptp(d) > 0


def _wilcoxon(d: np.ndarray, n_resamples: int, seed: int
              ) -> tuple[float, int, float | None]:
    """(two-sided p, zero differences, smallest attainable p)."""
    nonzero = d[d != 0]
    zeros, m = len(d) - len(nonzero), len(nonzero)
    if m == 0:
        return 1.0, zeros, None
    tied = len(np.unique(np.abs(nonzero))) < m
    if m > EXACT_MAX_PAIRS:
        method: str | stats.PermutationMethod = "asymptotic"
    elif tied:
        method = stats.PermutationMethod(n_resamples=n_resamples,
                                         rng=np.random.default_rng(seed))
    else:
        method = "exact"
    p = float(stats.wilcoxon(nonzero, zero_method="wilcox", method=method).pvalue)
    return min(p, 1.0), zeros, min(1.0, 2.0 ** (1 - m))


def sd_of_differences(sd_a: float, sd_b: float, correlation: float) -> float:
    """SD of a − b for SDs sd_a, sd_b and pair correlation ρ."""
    if sd_a < 0 or sd_b < 0 or not -1.0 <= correlation <= 1.0:
        raise ValueError(f"need SDs ≥ 0 and a correlation in [-1, 1], got {sd_a}, {sd_b}, "
                         f"{correlation}")
    return math.sqrt(max(sd_a**2 + sd_b**2 - 2.0 * correlation * sd_a * sd_b, 0.0))


def paired_power(n_pairs: int, diff: float, sd_diff: float, *, alpha: float = 0.05,
                 test: str = "wilcoxon") -> float:
    """Power of a two-sided paired test at level alpha to detect a true mean difference
    `diff` with SD(a − b) = sd_diff, over n_pairs pairs (module doc)."""
    if test not in POWER_TESTS:
        raise ValueError(f"test must be one of {POWER_TESTS}, got {test!r}")
    if not 0.0 < alpha < 1.0 or sd_diff <= 0 or n_pairs < 2:
        raise ValueError(f"need 0 < alpha < 1, sd_diff > 0 and ≥ 2 pairs, got {alpha}, "
                         f"{sd_diff}, {n_pairs}")
    if n_pairs < smallest_design(alpha, test):
        return 0.0  # no outcome of so few pairs reaches p ≤ alpha
    n = n_pairs * (WILCOXON_ARE if test == "wilcoxon" else 1.0)
    df = max(n - 1.0, 1e-9)
    ncp = abs(diff) / sd_diff * math.sqrt(n)
    crit = float(stats.t.ppf(1.0 - alpha / 2.0, df))
    wrong_side = float(stats.nct.cdf(-crit, df, ncp))  # NaN where it underflows (large ncp)
    return float(stats.nct.sf(crit, df, ncp)) + (0.0 if math.isnan(wrong_side) else wrong_side)


def minimum_detectable_effect(n_pairs: int, sd_diff: float, *, power: float = 0.8,
                              alpha: float = 0.05, test: str = "t") -> float:
    """The smallest true mean difference a two-sided paired test at level alpha detects with
    probability `power` over n_pairs pairs whose differences have SD sd_diff (in sd_diff's
    units): `paired_power` inverted. inf where no difference can reach that power (too few
    pairs for the Wilcoxon floor on p)."""
    if not 0.0 < power < 1.0:
        raise ValueError(f"need 0 < power < 1, got {power}")
    if sd_diff == 0:
        return 0.0
    if paired_power(n_pairs, sd_diff, sd_diff, alpha=alpha, test=test) == 0.0:
        return math.inf
    hi = sd_diff
    while paired_power(n_pairs, hi, sd_diff, alpha=alpha, test=test) < power:
        hi *= 2.0
    return float(optimize.brentq(
        lambda d: paired_power(n_pairs, d, sd_diff, alpha=alpha, test=test) - power,
        0.0, hi, xtol=1e-10 * sd_diff))


def smallest_design(alpha: float = 0.05, test: str = "wilcoxon") -> int:
    """The fewest pairs with which the test can reject at level alpha at all: 2 for the t-test,
    for the Wilcoxon test the first n with 2 / 2^n ≤ alpha (6 at α = 0.05)."""
    if test not in POWER_TESTS:
        raise ValueError(f"test must be one of {POWER_TESTS}, got {test!r}")
    if test == "t":
        return 2
    return max(2, math.ceil(math.log2(2.0 / alpha) - 1e-12))


def pairs_needed(diff: float, sd_a: float, sd_b: float, correlation: float, *,
                 power: float = 0.8, alpha: float = 0.05, test: str = "wilcoxon",
                 max_pairs: int = 100_000) -> int:
    """The fewest seed pairs with which a two-sided paired test at level alpha detects a true
    mean difference `diff` with probability `power`, for per-method SDs sd_a, sd_b and pair
    correlation ρ (module doc)."""
    if not 0.0 < power < 1.0 or diff == 0:
        raise ValueError(f"need 0 < power < 1 and a non-zero difference, got {power}, {diff}")
    sd = sd_of_differences(sd_a, sd_b, correlation)
    if sd == 0:  # no noise in the differences: the smallest design that can reject decides
        return smallest_design(alpha, test)
    lo, hi = 2, 2
    while paired_power(hi, diff, sd, alpha=alpha, test=test) < power:  # power rises with n
        lo, hi = hi, 2 * hi
        if hi > max_pairs:
            raise ValueError(f"more than {max_pairs} pairs needed for a difference of {diff}")
    while lo < hi:
        mid = (lo + hi) // 2
        if paired_power(mid, diff, sd, alpha=alpha, test=test) >= power:
            hi = mid
        else:
            lo = mid + 1
    return lo


# ---- intervals over runs (the report's headline; docs/reports.md) ---------------------------
# Collisions and false alarms happen per run and frames within a run are strongly correlated,
# so every headline interval resamples or counts runs, never frames.


@dataclass(frozen=True)
class Estimate:
    """A figure with its confidence interval (None where too few runs define one)."""

    value: float | None
    low: float | None
    high: float | None
    n: int  # the runs it rests on
    method: str | None  # "wilson", "bootstrap", "poisson-zero" or None (no interval)

    def to_dict(self) -> dict:
        return asdict(self)


def proportion_ci(successes: int, n: int, confidence: float = CONFIDENCE) -> Estimate:
    """successes / n with its Wilson score interval (`scipy.stats.binomtest`): unlike a bootstrap
    it is not degenerate at 0 or n successes, and it covers well at the handful of collision
    runs a scenario may have."""
    _check_confidence(confidence)
    if n == 0:
        return Estimate(None, None, None, 0, None)
    ci = stats.binomtest(successes, n).proportion_ci(confidence_level=confidence,
                                                     method="wilson")
    return Estimate(successes / n, float(ci.low), float(ci.high), n, "wilson")


def _percentile_ci(data: tuple[np.ndarray, ...], statistic, confidence: float,
                   n_resamples: int, seed: int) -> tuple[float, float]:
    ci = stats.bootstrap(data, statistic, paired=True, vectorized=True,
                         confidence_level=confidence, n_resamples=n_resamples,
                         method="percentile", rng=np.random.default_rng(seed)
                         ).confidence_interval
    return float(ci.low), float(ci.high)


def rate_ci(events: Sequence[int] | np.ndarray, exposure: Sequence[float] | np.ndarray, *,
            confidence: float = CONFIDENCE, n_resamples: int = N_RESAMPLES,
            seed: int = 0) -> Estimate:
    """Σ events / Σ exposure over runs (e.g. false alarms per hour of safe driving) with a
    percentile bootstrap interval resampling whole runs, which keeps a run's bursts of alarms
    together. With no event at all the bootstrap is degenerate; the interval is then [0, the
    one-sided Poisson bound −ln(1 − confidence) / Σ exposure]."""
    _check_confidence(confidence)
    e, x = np.asarray(events, float).reshape(-1), np.asarray(exposure, float).reshape(-1)
    if e.shape != x.shape:
        raise ValueError(f"one exposure per run: {len(e)} event counts, {len(x)} exposures")
    total = float(x.sum())
    if len(e) == 0 or total <= 0:
        return Estimate(None, None, None, len(e), None)
    value = float(e.sum()) / total
    if e.sum() == 0:
        bound = float(stats.chi2.ppf(confidence, 2) / 2) / total
        return Estimate(0.0, 0.0, bound, len(e), "poisson-zero")
    if len(e) < 2:
        return Estimate(value, None, None, 1, None)
    low, high = _percentile_ci((e, x), lambda a, b, axis=-1: a.sum(axis) / b.sum(axis),
                               confidence, n_resamples, seed)
    return Estimate(value, low, high, len(e), "bootstrap")


def poisson_ci(count: int, exposure: float, confidence: float = CONFIDENCE
               ) -> tuple[float | None, float | None]:
    """The exact (Garwood) two-sided interval of a Poisson rate: `count` events over `exposure`
    (e.g. hours); (None, None) without exposure. At 0 events the low end is 0 and the high end
    χ²(1 − α/2; 2)/2 / exposure: 3.69 / exposure at 95 %."""
    _check_confidence(confidence)
    if exposure <= 0:
        return None, None
    alpha = 1.0 - confidence
    low = float(stats.chi2.ppf(alpha / 2, 2 * count) / 2) if count > 0 else 0.0
    high = float(stats.chi2.ppf(1 - alpha / 2, 2 * count + 2) / 2)
    return low / exposure, high / exposure


def median_ci(values: Sequence[float] | np.ndarray, *, confidence: float = CONFIDENCE,
              n_resamples: int = N_RESAMPLES, seed: int = 0) -> Estimate:
    """The median of per-run values (e.g. lead times) with a percentile bootstrap interval
    (None below two values)."""
    _check_confidence(confidence)
    a = _finite(values)
    if len(a) == 0:
        return Estimate(None, None, None, 0, None)
    if len(a) < 2:
        return Estimate(float(a[0]), None, None, 1, None)
    if np.ptp(a) == 0:  # every resample has the same median
        return Estimate(float(a[0]), float(a[0]), float(a[0]), len(a), "bootstrap")
    low, high = _percentile_ci((a,), lambda v, axis=-1: np.median(v, axis=axis), confidence,
                               n_resamples, seed)
    return Estimate(float(np.median(a)), low, high, len(a), "bootstrap")


def paired_warnings_p(a: Sequence[bool] | np.ndarray, b: Sequence[bool] | np.ndarray) -> float:
    """Two-sided exact McNemar p of two monitors warned (or not) on the same runs: the binomial
    test of the runs only one of them warned of (1.0 when there are none)."""
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    if a.shape != b.shape:
        raise ValueError(f"paired runs need one flag each: {a.shape} against {b.shape}")
    only_a, only_b = int((a & ~b).sum()), int((b & ~a).sum())
    if only_a + only_b == 0:
        return 1.0
    return float(stats.binomtest(only_a, only_a + only_b, 0.5).pvalue)
