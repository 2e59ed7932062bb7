"""Thresholds for a target false-positive rate, chosen on validation scores (paper §V "Metrics").

One function for every monitor (FusionMonitor, AEM, TTC, RSS, the control; RQ1, RQ2 and the
AEM-Evo): `calibrate_on_validation`, on a monitor's scores of the validation windows
`load_windows` returns — pre-collision frames only (view eligible_frames).

A frame alarms when its score is strictly above the threshold. For each target FPR α the
threshold is the lowest negative score at which at most a share α of the negatives score above
it. Ties are therefore resolved by value, never by order: frames tied at the threshold all stay
silent, so the same scores give the same thresholds whatever order they come in. The FPR this
realises on the calibration split is kept next to the target.

When more than a share α of the negatives tie at the top negative score, the only threshold
that meets α is that top score. If no calibration frame scores above it either, the monitor
raises no alarm at all at α on the split it was calibrated on: α is *unreachable* for it and is
marked so (`Thresholds.unreachable`), and every metric table reports it as unreachable instead
of a recall or F1 of 0.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from evoeye.monitor.protocol import TARGET_FPRS, Thresholds
from evoeye.store.windows import Windows


def calibrate(scores: np.ndarray, labels: np.ndarray,
              fprs: Iterable[float] = TARGET_FPRS) -> Thresholds:
    """Per target FPR, the lowest threshold whose alarms (score > threshold) on the negatives
    of this split are at most that rate, the rate it realises, and which targets are
    unreachable (module doc)."""
    scores, labels = np.asarray(scores, dtype=float), np.asarray(labels)
    if scores.shape != labels.shape or scores.ndim != 1:
        raise ValueError(f"{scores.shape} scores for {labels.shape} labels")
    if not np.isfinite(scores).all():
        raise ValueError("cannot calibrate on non-finite scores")
    neg = scores[labels == 0]
    if neg.size == 0:
        raise ValueError("cannot calibrate a false-positive rate without negative frames")
    values, counts = np.unique(neg, return_counts=True)  # ascending distinct negative scores
    above = (neg.size - np.cumsum(counts)) / neg.size  # share of negatives above each value
    top = float(scores.max())
    by_fpr, realised, unreachable = {}, {}, set()
    for fpr in fprs:
        if not 0.0 < fpr < 1.0:
            raise ValueError(f"target FPR must be in (0, 1), got {fpr}")
        i = int(np.argmax(above <= fpr))  # the last value has nothing above it: always found
        fpr = float(fpr)
        by_fpr[fpr], realised[fpr] = float(values[i]), float(above[i])
        if values[i] >= top:  # no calibration frame, negative or positive, would alarm
            unreachable.add(fpr)
    return Thresholds(by_fpr, realised, frozenset(unreachable))


def calibrate_on_validation(scores: np.ndarray, val: Windows,
                            fprs: Iterable[float] = TARGET_FPRS) -> Thresholds:
    """Thresholds from a monitor's (B,) scores of the validation windows `val` (from
    `load_windows`, so no frame at or after a collision), against their labels."""
    scores = np.asarray(scores)
    if scores.shape != (len(val),):
        raise ValueError(f"{scores.shape} scores for {len(val)} validation windows")
    return calibrate(scores, val.label, fprs)


def alarms(scores: np.ndarray, threshold: float) -> np.ndarray:
    """(B,) bool: the monitor raises an alarm where its score exceeds the threshold."""
    return np.asarray(scores) > threshold
