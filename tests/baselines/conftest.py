"""Hand-built windows (no warehouse): one frame per window, obstacles placed by the test."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.store.features import (
    CONTROL_FEATURES,
    FEATURES,
    PERCEPTION_FEATURES,
    FrameFeatures,
)
from evoeye.store.windows import Windows

EGO_SPEED = CONTROL_FEATURES.index("ego_speed_mps")


def obstacle(dx_m: float, dy_m: float, dvx_mps: float = 0.0, dvy_mps: float = 0.0,
             length_m: float = 5.0, width_m: float = 2.0) -> np.ndarray:
    """One perception row (ego frame), heading aligned with the ego."""
    values = {"dx_m": dx_m, "dy_m": dy_m, "cos_dheading": 1.0, "sin_dheading": 0.0,
              "dvx_mps": dvx_mps, "dvy_mps": dvy_mps, "length_m": length_m,
              "width_m": width_m, "confidence": 1.0}
    return np.array([values[k] for k in PERCEPTION_FEATURES], np.float32)


def make_windows(frames: list[list[np.ndarray]], ego_speed_mps: list[float] | None = None
                 ) -> Windows:
    """L = 1 windows, one per frame; frame i perceives the obstacles frames[i]."""
    n = len(frames)
    f = FrameFeatures.empty(n, FEATURES)
    for i, obstacles in enumerate(frames):
        for j, row in enumerate(obstacles):
            f.perception[i, j] = row
            f.perception_mask[i, j] = True
    f.control[:, EGO_SPEED] = ego_speed_mps or [0.0] * n
    return Windows(
        f, np.arange(n)[:, None], np.ones((n, 1), bool), np.zeros(n, np.int8),
        np.array([f"s{i}" for i in range(n)], dtype=object), np.zeros(n, np.int32),
        np.zeros(n), 3.0, FEATURES,
    )


@pytest.fixture
def windows_of():
    return make_windows


@pytest.fixture
def obs():
    return obstacle
