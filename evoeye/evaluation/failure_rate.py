"""How often the ADS fails under the scenario distribution p, from runs drawn from a proposal q.

Runs acquired by an importance-sampling strategy (`ce-is`) are drawn from q ≠ p, each with its
exact weight w = p/q (`Records.importance_ratio`; 1 for a run drawn from p). Two estimates of
P_p(collision) from n such runs with outcomes y ∈ {0, 1}:

* importance sampling, `failure_rate(..., "is")`: P̂ = mean(w·y). Unbiased whenever q > 0 where
  p·y > 0 (the defensive mixture guarantees it). Its standard error is the sample SD of w·y
  over √n; the interval is P̂ ± t·SE (the central limit theorem over runs, as the rare-event
  simulation literature reports it).
* self-normalised, `"self-normalised"`: P̃ = Σ w·y / Σ w. Biased by O(1/n), but needs w only up to
  a constant, and its error is often smaller when the weights vary much; SE by the delta method,
  √(Σ w²·(y − P̃)²) / Σ w.

Plain Monte Carlo (every w = 1) is the special case: both reduce to the share of runs that
collided. The relative error SE / P̂ is what an equal budget is compared on: for plain Monte
Carlo it is √((1 − P) / (n·P)), 10 at P = 0.1 % and n = 100.

With no collision among the runs both estimates are 0 and the SE says nothing; the interval is
then [0, −ln(1 − confidence) · max w / n]: a run of weight w that had collided would have added
w / n, and with none in n runs the Poisson rule of three bounds their mean (conservative, as
each run's weight is at most the largest one seen; for plain Monte Carlo it is the rule of
three itself).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
from scipy import stats

from evoeye.evaluation.stats import CONFIDENCE

ESTIMATORS = ("is", "self-normalised")


@dataclass(frozen=True)
class FailureRate:
    """An estimate of P_p(collision) with its standard error and interval."""

    value: float | None
    low: float | None
    high: float | None
    se: float | None
    relative_error: float | None  # se / value; None at value 0
    n: int  # runs
    collisions: int
    effective_runs: float  # Kish's (Σ w)² / Σ w²: n for plain Monte Carlo
    method: str  # ESTIMATORS

    def to_dict(self) -> dict:
        return asdict(self)


def failure_rate(collided: Sequence[bool] | np.ndarray, ratio: Sequence[float] | np.ndarray,
                 method: str = "is", confidence: float = CONFIDENCE) -> FailureRate:
    """P_p(collision) from runs' outcomes (n,) and their weights p/q (n,) (module doc);
    ValueError for unequal lengths, a weight that is not finite and > 0, or an unknown method."""
    if method not in ESTIMATORS:
        raise ValueError(f"unknown failure-rate estimator {method!r}; known: {list(ESTIMATORS)}")
    y = np.asarray(collided, dtype=bool).reshape(-1).astype(float)
    w = np.asarray(ratio, dtype=float).reshape(-1)
    if y.shape != w.shape:
        raise ValueError(f"one weight per run: {len(y)} outcomes, {len(w)} weights")
    if not (np.isfinite(w) & (w > 0)).all():
        raise ValueError("every weight p/q must be finite and > 0")
    n = len(y)
    if n == 0:
        return FailureRate(None, None, None, None, None, 0, 0, 0.0, method)
    hits = int(y.sum())
    ess = float(w.sum() ** 2 / (w**2).sum())
    if hits == 0:
        bound = -math.log(1.0 - confidence) * float(w.max()) / n
        return FailureRate(0.0, 0.0, bound, None, None, n, 0, ess, method)
    if method == "is":
        value = float((w * y).mean())
        se = float((w * y).std(ddof=1) / math.sqrt(n)) if n > 1 else None
    else:
        value = float((w * y).sum() / w.sum())
        se = float(math.sqrt(((w * (y - value)) ** 2).sum()) / w.sum())
    if se is None:
        return FailureRate(value, None, None, None, None, n, hits, ess, method)
    half = float(stats.t.ppf(0.5 + confidence / 2, max(n - 1, 1))) * se
    return FailureRate(value, max(0.0, value - half), value + half, se, se / value, n, hits,
                       ess, method)
