"""Calibration: thresholds meet the target FPR on the split they were chosen on, ties are resolved
by value, the realised FPR is kept, and an unreachable target is marked, never hidden."""

import numpy as np
import pytest
from sklearn.metrics import roc_curve

from evoeye.monitor.calibration import alarms, calibrate


def test_thresholds_meet_each_target_fpr_on_their_split():
    rng = np.random.default_rng(0)
    scores = np.concatenate([rng.uniform(0, 1, 10_000), rng.uniform(0.5, 1, 500)])
    labels = np.concatenate([np.zeros(10_000), np.ones(500)])
    th = calibrate(scores, labels)
    for fpr in (0.05, 0.01):
        realised = alarms(scores[labels == 0], th.at(fpr)).mean()
        assert realised <= fpr and realised > fpr - 0.002  # as many alarms as allowed
        assert th.realised_fpr[fpr] == realised and th.reachable(fpr)
    assert th.at(0.01) > th.at(0.05)


def test_the_realised_fpr_is_the_best_roc_point_within_the_target():
    """Against scikit-learn's ROC: no threshold gives more alarms within the target FPR."""
    rng = np.random.default_rng(1)
    scores = np.round(rng.beta(2, 5, 3000), 2)  # coarse: many ties
    labels = rng.random(3000) < 0.1
    th = calibrate(scores, labels, fprs=(0.2, 0.05, 0.01))
    roc_fpr, _, _ = roc_curve(labels, scores, drop_intermediate=False)
    for fpr in (0.2, 0.05, 0.01):
        assert th.realised_fpr[fpr] == pytest.approx(roc_fpr[roc_fpr <= fpr].max())
        lower = np.unique(scores[~labels])
        lower = lower[lower < th.at(fpr)]
        if len(lower):  # the next lower threshold would break the target
            assert alarms(scores[~labels], lower[-1]).mean() > fpr


def test_ties_never_push_the_fpr_over_target():
    scores = np.array([0.0] * 90 + [0.5] * 10 + [0.9] * 5)
    labels = np.array([0] * 100 + [1] * 5)
    th = calibrate(scores, labels, fprs=(0.05,))
    assert alarms(scores[:100], th.at(0.05)).mean() <= 0.05
    assert th.at(0.05) == 0.5 and th.realised_fpr[0.05] == 0.0  # the tied 10 % stay silent
    assert th.reachable(0.05)  # the positives at 0.9 still alarm


def test_ties_at_the_top_score_make_a_target_unreachable():
    # TTC-like: 3 % of the negatives and every positive score the maximum risk 1.0
    neg = np.concatenate([np.linspace(0.0, 0.9, 97), np.ones(3)])
    scores = np.concatenate([neg, np.ones(10)])
    labels = np.array([0] * 100 + [1] * 10)
    th = calibrate(scores, labels, fprs=(0.05, 0.01))
    assert th.reachable(0.05) and th.realised_fpr[0.05] == pytest.approx(0.05)
    assert th.at(0.05) == pytest.approx(0.9 * 94 / 96)  # the tied 3 % and 2 more alarm
    assert not th.reachable(0.01) and th.unreachable == {0.01}
    assert th.at(0.01) == 1.0 and th.realised_fpr[0.01] == 0.0
    assert not alarms(scores, th.at(0.01)).any()  # no frame can alarm at this threshold


def test_a_top_tie_is_reachable_when_positives_score_above_it():
    scores = np.array([0.0] * 95 + [0.5] * 5 + [0.8] * 4)
    labels = np.array([0] * 100 + [1] * 4)
    th = calibrate(scores, labels, fprs=(0.01,))
    assert th.at(0.01) == 0.5 and th.realised_fpr[0.01] == 0.0 and th.reachable(0.01)


def test_calibration_is_deterministic_whatever_the_order():
    rng = np.random.default_rng(2)
    scores = np.round(rng.random(500), 1)
    labels = (rng.random(500) < 0.2).astype(int)
    th = calibrate(scores, labels, fprs=(0.1, 0.05, 0.01))
    assert calibrate(scores, labels, fprs=(0.1, 0.05, 0.01)) == th
    for _ in range(5):
        p = rng.permutation(500)
        assert calibrate(scores[p], labels[p], fprs=(0.1, 0.05, 0.01)) == th


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="negative"):
        calibrate(np.ones(3), np.ones(3))
    with pytest.raises(ValueError, match="FPR"):
        calibrate(np.zeros(3), np.zeros(3), fprs=(1.5,))
    with pytest.raises(ValueError, match="non-finite"):
        calibrate(np.array([0.1, np.nan]), np.zeros(2))
    with pytest.raises(ValueError, match="labels"):
        calibrate(np.zeros(3), np.zeros(4))
    with pytest.raises(KeyError, match="0.2"):
        calibrate(np.zeros(3), np.zeros(3)).at(0.2)
    with pytest.raises(KeyError, match="0.2"):
        calibrate(np.zeros(3), np.zeros(3)).reachable(0.2)
