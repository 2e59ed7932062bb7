"""Calibration: thresholds meet the target FPR on the split they were chosen on."""

import numpy as np
import pytest

from evoeye.monitor.calibration import alarms, calibrate


def test_thresholds_meet_each_target_fpr_on_their_split():
    rng = np.random.default_rng(0)
    scores = np.concatenate([rng.uniform(0, 1, 10_000), rng.uniform(0.5, 1, 500)])
    labels = np.concatenate([np.zeros(10_000), np.ones(500)])
    th = calibrate(scores, labels)
    for fpr in (0.05, 0.01):
        realised = alarms(scores[labels == 0], th.at(fpr)).mean()
        assert realised <= fpr and realised > fpr - 0.002  # as many alarms as allowed
    assert th.at(0.01) > th.at(0.05)


def test_ties_never_push_the_fpr_over_target():
    scores = np.array([0.0] * 90 + [0.5] * 10 + [0.9] * 5)
    labels = np.array([0] * 100 + [1] * 5)
    th = calibrate(scores, labels, fprs=(0.05,))
    assert alarms(scores[:100], th.at(0.05)).mean() <= 0.05


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="negative"):
        calibrate(np.ones(3), np.ones(3))
    with pytest.raises(ValueError, match="FPR"):
        calibrate(np.zeros(3), np.zeros(3), fprs=(1.5,))
    with pytest.raises(KeyError, match="0.2"):
        calibrate(np.zeros(3), np.zeros(3)).at(0.2)
