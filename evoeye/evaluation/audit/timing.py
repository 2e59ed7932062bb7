"""Does the clock give the danger away? Collision-time spread, and the AUROC of time alone.

The clock check runs on pre-collision frames only (labels: Definition 1). Three scores of the
time since start t: −t ("earlier = riskier"), the better of ±t, and a gradient-boosted model of
t alone, scored out of fold with folds grouped by run. The headline is the largest of the three:
how far a monitor could get by reading the clock.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
from sklearn.base import ClassifierMixin
from sklearn.ensemble import HistGradientBoostingClassifier
from sklearn.model_selection import GroupKFold
from threadpoolctl import threadpool_limits

from evoeye.evaluation.metrics import auroc

QUANTILES = (0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0)
BIN_S = 1.0
CLOCK_FOLDS = 5


@dataclass(frozen=True)
class CollisionTimes:
    """Quantiles, a 1 s histogram and the share of the fullest bin of collision times."""

    n: int
    quantiles_s: dict[str, float]  # "q50" → s
    bin_s: float
    counts: tuple[int, ...]  # collisions in [k·bin_s, (k+1)·bin_s)
    top_bin_start_s: float
    top_bin_share: float

    def to_dict(self) -> dict:
        return asdict(self)


def collision_times(times_s: np.ndarray, bin_s: float = BIN_S) -> CollisionTimes | None:
    """The distribution of collision times (s); None without collisions."""
    t = np.asarray(times_s, dtype=float)
    if len(t) == 0:
        return None
    q = np.quantile(t, QUANTILES)
    counts = np.bincount(np.floor(t / bin_s).astype(np.int64))
    top = int(np.argmax(counts))
    return CollisionTimes(
        n=len(t), quantiles_s={f"q{round(100 * p)}": float(v) for p, v in zip(QUANTILES, q,
                                                                             strict=True)},
        bin_s=bin_s, counts=tuple(int(c) for c in counts), top_bin_start_s=top * bin_s,
        top_bin_share=float(counts[top] / len(t)),
    )


def histogram_lines(times: CollisionTimes, width: int = 40) -> list[str]:
    """A text histogram, one line per bin: range, bar, count."""
    peak = max(times.counts)
    return [
        f"{k * times.bin_s:5.1f}–{(k + 1) * times.bin_s:<5.1f} s "
        f"{'█' * round(width * c / peak):<{width}} {c}"
        for k, c in enumerate(times.counts)
    ]


@dataclass(frozen=True)
class ClockAuroc:
    """AUROC of time-only scores on pre-collision frames; None where a class is missing."""

    frames: int
    unsafe_frames: int
    runs: int
    earlier_riskier: float | None  # score −t
    best_direction: float | None  # max over ±t
    model: float | None  # out-of-fold gradient boosting on t

    @property
    def headline(self) -> float | None:
        values = [v for v in (self.earlier_riskier, self.best_direction, self.model)
                  if v is not None]
        return max(values) if values else None

    def to_dict(self) -> dict:
        return {**asdict(self), "headline": self.headline}


def out_of_fold_scores(x: np.ndarray, labels: np.ndarray, groups: np.ndarray,
                       make_model: Callable[[], ClassifierMixin],
                       folds: int = CLOCK_FOLDS) -> np.ndarray | None:
    """(N,) out-of-fold P(unsafe | x) of the classifier `make_model` builds, for x (N, F),
    folds grouped by run (a fold trained on one class predicts its training rate); None with
    fewer runs than 2 or a single class."""
    n_groups = len(np.unique(groups))
    if n_groups < 2 or labels.min() == labels.max():
        return None
    scores = np.empty(len(x))
    # One OpenMP thread: on a shared machine its threads oversubscribe the cores (measured 20×
    # slower at load 8 on 2 cores), and a model of a few features gains nothing from them.
    with threadpool_limits(1):
        for train, test in GroupKFold(n_splits=min(folds, n_groups)).split(x, labels, groups):
            y = labels[train]
            if y.min() == y.max():
                scores[test] = y[0]
                continue
            scores[test] = make_model().fit(x[train], y).predict_proba(x[test])[:, 1]
    return scores


def clock_model_scores(t_s: np.ndarray, labels: np.ndarray, groups: np.ndarray,
                       folds: int = CLOCK_FOLDS) -> np.ndarray | None:
    """(N,) out-of-fold P(unsafe | t) from a gradient-boosted model of t alone."""
    return out_of_fold_scores(
        t_s[:, None], labels, groups, folds=folds,
        make_model=lambda: HistGradientBoostingClassifier(max_iter=100, early_stopping=False,
                                                          random_state=0))


def clock_auroc(t_s: np.ndarray, labels: np.ndarray, groups: np.ndarray) -> ClockAuroc:
    """The clock-only AUROCs of eligible frames: t_s, labels and run ids, each (N,)."""
    t_s, labels = np.asarray(t_s, float), np.asarray(labels, np.int64)
    earlier = auroc(-t_s, labels)
    model = clock_model_scores(t_s, labels, np.asarray(groups))
    return ClockAuroc(
        frames=len(t_s), unsafe_frames=int(labels.sum()), runs=len(np.unique(groups)),
        earlier_riskier=earlier,
        best_direction=None if earlier is None else max(earlier, 1.0 - earlier),
        model=None if model is None else auroc(model, labels),
    )
