"""Frame-level metrics (paper §V "Metrics"): P / R / F1 at calibrated thresholds, AUROC, AUPRC."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from sklearn.metrics import (
    average_precision_score,
    precision_recall_curve,
    roc_auc_score,
    roc_curve,
)

from evoeye.monitor.calibration import alarms
from evoeye.monitor.protocol import Thresholds

CURVE_POINTS = 200  # points kept per curve for reports


@dataclass(frozen=True)
class PRF:
    """Confusion counts and the rates derived from them (0 where a rate is undefined); sums of
    the frames' weights where the set is weighted (`prf`'s `weight`).

    At a threshold whose target FPR was unreachable on validation (`reachable` False,
    `evoeye.monitor.calibration`) precision, recall and F1 are None: no operating point at that
    FPR exists to measure, and a 0 would read as a monitor that misses everything.
    """

    tp: float
    fp: float
    fn: float
    tn: float
    reachable: bool = True

    @property
    def precision(self) -> float | None:
        if not self.reachable:
            return None
        return self.tp / (self.tp + self.fp) if self.tp + self.fp else 0.0

    @property
    def recall(self) -> float | None:
        if not self.reachable:
            return None
        return self.tp / (self.tp + self.fn) if self.tp + self.fn else 0.0

    @property
    def f1(self) -> float | None:
        p, r = self.precision, self.recall
        if p is None or r is None:
            return None
        return 2 * p * r / (p + r) if p + r else 0.0

    @property
    def fpr(self) -> float:
        return self.fp / (self.fp + self.tn) if self.fp + self.tn else 0.0

    def to_dict(self) -> dict[str, float | int | bool | None]:
        return {"precision": self.precision, "recall": self.recall, "f1": self.f1,
                "fpr": self.fpr, "tp": self.tp, "fp": self.fp, "fn": self.fn, "tn": self.tn,
                "reachable": self.reachable}


def prf(predicted: np.ndarray, labels: np.ndarray, reachable: bool = True,
        weight: np.ndarray | None = None) -> PRF:
    """Counts of predicted-positive vs true labels (both (N,), truthy = positive); with
    `weight` (N,), the sums of the frames' weights instead (a stratified set, each frame
    standing for `weight` frames of the population)."""
    p, y = np.asarray(predicted, bool), np.asarray(labels, bool)
    cells = (p & y, p & ~y, ~p & y, ~p & ~y)
    if weight is None:
        return PRF(*(int(c.sum()) for c in cells), reachable)
    w = np.asarray(weight, float)
    return PRF(*(float(w[c].sum()) for c in cells), reachable)


def auroc(scores: np.ndarray, labels: np.ndarray,
          weight: np.ndarray | None = None) -> float | None:
    """Area under the ROC curve (each frame weighted by `weight`, if given); None when only
    one class is present."""
    y = np.asarray(labels, bool)
    return (float(roc_auc_score(y, scores, sample_weight=weight)) if 0 < y.sum() < len(y)
            else None)


def auprc(scores: np.ndarray, labels: np.ndarray,
          weight: np.ndarray | None = None) -> float | None:
    """Area under the precision-recall curve (average precision; each frame weighted by
    `weight`, if given); None without positives."""
    y = np.asarray(labels, bool)
    return (float(average_precision_score(y, scores, sample_weight=weight))
            if 0 < y.sum() < len(y) else None)


def _thin(*arrays: np.ndarray, n: int = CURVE_POINTS) -> list[list[float]]:
    """Keep about n points of parallel curve arrays (always the first and the last)."""
    m = len(arrays[0])
    keep = np.unique(np.linspace(0, m - 1, min(n, m)).round().astype(int)) if m else []
    return [np.round(a[keep], 5).tolist() for a in arrays]


@dataclass(frozen=True)
class Curves:
    """ROC (fpr, tpr) and PR (recall, precision) points, thinned for plotting."""

    roc_fpr: list[float]
    roc_tpr: list[float]
    pr_recall: list[float]
    pr_precision: list[float]

    @classmethod
    def of(cls, scores: np.ndarray, labels: np.ndarray) -> Curves:
        y = np.asarray(labels, bool)
        if not 0 < y.sum() < len(y):
            return cls([], [], [], [])
        fpr, tpr, _ = roc_curve(y, scores)
        precision, recall, _ = precision_recall_curve(y, scores)
        return cls(*_thin(fpr, tpr), *_thin(recall[::-1], precision[::-1]))


@dataclass(frozen=True)
class FrameMetrics:
    """Frame-level results of one monitor on one test split."""

    at_fpr: dict[float, PRF]  # target FPR → counts at the threshold calibrated for it
    auroc: float | None
    auprc: float | None
    frames: int
    unsafe_frames: int

    def to_dict(self) -> dict:
        return {
            "at_fpr": {str(k): v.to_dict() for k, v in self.at_fpr.items()},
            "auroc": self.auroc, "auprc": self.auprc,
            "frames": self.frames, "unsafe_frames": self.unsafe_frames,
        }


def frame_metrics(scores: np.ndarray, labels: np.ndarray, thresholds: Thresholds,
                  fprs: Iterable[float] | None = None,
                  weight: np.ndarray | None = None) -> FrameMetrics:
    """P / R / F1 at each calibrated threshold (alarm: score > threshold), AUROC, AUPRC; with
    `weight`, of a weighted (stratified) set: every count and area weighs each frame by it
    (`frames` and `unsafe` stay the frames' numbers)."""
    scores, labels = np.asarray(scores, float), np.asarray(labels).astype(bool)
    fprs = sorted(thresholds.by_fpr, reverse=True) if fprs is None else list(fprs)
    return FrameMetrics(
        {f: prf(alarms(scores, thresholds.at(f)), labels, thresholds.reachable(f), weight)
         for f in fprs},
        auroc(scores, labels, weight), auprc(scores, labels, weight), len(labels),
        int(labels.sum()),
    )
