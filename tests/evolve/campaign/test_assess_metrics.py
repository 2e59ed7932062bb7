"""A set's metrics as a campaign stores them, and which of them were measured."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.evolve.campaign.assess import metrics_dict, reached
from evoeye.monitor.protocol import Thresholds

# FPR 0.01 unreachable on validation: its threshold is kept, its rates are not measurements
THRESHOLDS = Thresholds({0.05: 0.5, 0.01: 0.9}, {0.05: 0.05, 0.01: 0.2}, frozenset({0.01}))


def test_a_metric_at_an_unreachable_fpr_is_none_and_not_reached() -> None:
    m = metrics_dict(np.array([0.2, 0.7, 0.95]), np.array([0, 1, 1]), THRESHOLDS)
    assert m["f1@0.05"] == pytest.approx(1.0) and m["f1@0.01"] is None
    assert reached(m, "f1@0.05") and reached(m, "recall@0.05")
    assert not reached(m, "f1@0.01") and not reached(m, "precision@0.01")
    assert reached(m, "auroc") and reached(m, "frames")  # no FPR: always measured


def test_a_set_of_sizes_only_counts_as_reached() -> None:
    sizes = {"frames": 4, "unsafe": 0}  # the results' set without unsafe frames: undefined
    assert reached(sizes, "f1@0.05") and reached(sizes, "auroc")
