"""A set's figures and their mean over a final monitor's k training seeds."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.monitor.protocol import Thresholds
from evoeye.results.rq2 import mean_figures
from evoeye.results.units import set_metrics

THRESHOLDS = Thresholds({0.05: 0.5, 0.01: 0.9}, {0.05: 0.05, 0.01: 0.01})


def test_a_set_without_unsafe_frames_has_sizes_and_no_rates() -> None:
    assert set_metrics(np.array([0.2, 0.7]), np.array([0, 0]), THRESHOLDS) == {
        "frames": 2, "unsafe": 0}  # not an F1 of 0
    m = set_metrics(np.array([0.2, 0.7, 0.95]), np.array([0, 1, 1]), THRESHOLDS)
    assert m["f1@0.05"] == pytest.approx(1.0) and m["recall@0.01"] == pytest.approx(0.5)


def test_the_mean_over_k_seeds_leaves_undefined_figures_out() -> None:
    per_seed = [{"hard": {"f1@0.05": 0.2, "auroc": 0.6, "reachable@0.05": True}},
                {"hard": {"f1@0.05": None, "auroc": 0.8, "reachable@0.05": False}},
                {"hard": {"f1@0.05": 0.4, "auroc": None, "reachable@0.05": True}}]
    mean = mean_figures(per_seed)["hard"]
    assert mean["f1@0.05"] == pytest.approx(0.3) and mean["auroc"] == pytest.approx(0.7)
    assert mean["reachable@0.05"] is True
    none = mean_figures([{"s": {"f1@0.05": None, "reachable@0.05": False}}] * 3)["s"]
    assert none == {"f1@0.05": None, "reachable@0.05": False}
    empty = mean_figures([{"robust": {"frames": 9, "unsafe": 0}}] * 2)["robust"]
    assert empty == {"frames": 9.0, "unsafe": 0.0}
