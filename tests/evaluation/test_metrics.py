"""Frame-level metrics against hand-computed values on a 10-frame example."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.evaluation.metrics import Curves, frame_metrics, prf
from evoeye.monitor.protocol import Thresholds

SCORES = np.array([0.9, 0.8, 0.7, 0.6, 0.55, 0.5, 0.4, 0.3, 0.2, 0.1])
LABELS = np.array([1, 1, 0, 1, 0, 0, 1, 0, 0, 0])
THRESHOLDS = Thresholds({0.05: 0.65, 0.01: 0.85})


def test_precision_recall_f1_at_each_threshold() -> None:
    m = frame_metrics(SCORES, LABELS, THRESHOLDS)
    loose, strict = m.at_fpr[0.05], m.at_fpr[0.01]
    # score > 0.65: frames 0, 1, 2 alarm -> tp 2, fp 1, fn 2, tn 5
    assert (loose.tp, loose.fp, loose.fn, loose.tn) == (2, 1, 2, 5)
    assert loose.precision == pytest.approx(2 / 3) and loose.recall == pytest.approx(0.5)
    assert loose.f1 == pytest.approx(4 / 7) and loose.fpr == pytest.approx(1 / 6)
    # score > 0.85: frame 0 only
    assert (strict.precision, strict.recall, strict.f1) == pytest.approx((1.0, 0.25, 0.4))
    assert m.frames == 10 and m.unsafe_frames == 4


def test_auroc_and_auprc_by_hand() -> None:
    m = frame_metrics(SCORES, LABELS, THRESHOLDS)
    # positives beat 6 + 6 + 5 + 3 of the 4 x 6 (positive, negative) pairs
    assert m.auroc == pytest.approx(20 / 24)
    # positives at ranks 1, 2, 4, 7: precision 1, 1, 3/4, 4/7 there
    assert m.auprc == pytest.approx((1 + 1 + 0.75 + 4 / 7) / 4)


def test_undefined_rates_are_zero_and_one_class_has_no_auc() -> None:
    none = prf(np.zeros(4, bool), np.zeros(4, bool))
    assert (none.precision, none.recall, none.f1, none.fpr) == (0.0, 0.0, 0.0, 0.0)
    m = frame_metrics(SCORES, np.zeros(10), THRESHOLDS)
    assert m.auroc is None and m.auprc is None


def test_curves_start_and_end_at_the_corners() -> None:
    c = Curves.of(SCORES, LABELS)
    assert (c.roc_fpr[0], c.roc_tpr[0], c.roc_fpr[-1], c.roc_tpr[-1]) == (0, 0, 1, 1)
    assert c.pr_recall[0] == 0.0 and c.pr_recall[-1] == 1.0
    assert c.pr_precision[-1] == pytest.approx(0.4)  # every frame alarms: 4 / 10


def test_an_unreachable_operating_point_has_no_rates_but_keeps_its_counts() -> None:
    thr = Thresholds({0.05: 0.65, 0.01: 0.85}, {0.05: 0.04, 0.01: 0.0}, frozenset({0.01}))
    m = frame_metrics(SCORES, LABELS, thr)
    assert m.at_fpr[0.05].reachable and m.at_fpr[0.05].f1 == pytest.approx(4 / 7)
    strict = m.at_fpr[0.01]
    assert (strict.precision, strict.recall, strict.f1) == (None, None, None)
    assert (strict.tp, strict.fp) == (1, 0) and strict.fpr == 0.0
    assert strict.to_dict()["reachable"] is False and strict.to_dict()["f1"] is None


def test_a_weighted_set_scores_as_the_set_its_weights_stand_for() -> None:
    # frame i weighs w[i]: the same as frame i repeated w[i] times
    weight = np.array([1, 3, 2, 1, 4, 1, 2, 5, 1, 3])
    weighted = frame_metrics(SCORES, LABELS, THRESHOLDS, weight=weight)
    repeated = frame_metrics(np.repeat(SCORES, weight), np.repeat(LABELS, weight), THRESHOLDS)
    assert weighted.auroc == pytest.approx(repeated.auroc)
    assert weighted.auprc == pytest.approx(repeated.auprc)
    for fpr in THRESHOLDS.by_fpr:
        a, b = weighted.at_fpr[fpr], repeated.at_fpr[fpr]
        assert (a.tp, a.fp, a.fn, a.tn) == (b.tp, b.fp, b.fn, b.tn)
        assert (a.precision, a.recall) == pytest.approx((b.precision, b.recall))
    assert weighted.auprc != pytest.approx(frame_metrics(SCORES, LABELS, THRESHOLDS).auprc)
    assert weighted.frames == 10 and weighted.unsafe_frames == 4  # the frames themselves
