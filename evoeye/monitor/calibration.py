"""Thresholds for a target false-positive rate, chosen on validation scores (paper §V "Metrics").

One convention for RQ1, RQ2 and the AEM: `calibrate_on_validation`, on a monitor's scores of the
validation windows `load_windows` returns — pre-collision frames only (view eligible_frames).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from evoeye.monitor.protocol import TARGET_FPRS, Thresholds
from evoeye.store.windows import Windows


def calibrate(scores: np.ndarray, labels: np.ndarray,
              fprs: Iterable[float] = TARGET_FPRS) -> Thresholds:
    """Per target FPR, the lowest threshold whose alarms (score > threshold) on the negatives
    of this split are at most that rate."""
    scores, labels = np.asarray(scores, dtype=float), np.asarray(labels)
    neg = scores[labels == 0]
    if neg.size == 0:
        raise ValueError("cannot calibrate a false-positive rate without negative frames")
    out = {}
    for fpr in fprs:
        if not 0.0 < fpr < 1.0:
            raise ValueError(f"target FPR must be in (0, 1), got {fpr}")
        out[float(fpr)] = float(np.quantile(neg, 1.0 - fpr, method="higher"))
    return Thresholds(out)


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
