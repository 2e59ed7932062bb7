"""Localization: the ego's own state estimate."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from evoeye.ads.config import LocalizationConfig
from evoeye.ads.messages import Localization
from evoeye.scene import SceneState


class Localizer(Protocol):
    """Estimates the ego's state from the scene."""

    def localize(self, scene: SceneState) -> Localization: ...


class NoisyLocalizer:
    """The ego's true state (row 0) with independent Gaussian noise on every field."""

    def __init__(self, config: LocalizationConfig, rng: np.random.Generator) -> None:
        self.rng = rng
        self.sigma = np.array([
            config.pos_sigma_m, config.pos_sigma_m, config.heading_sigma_rad,
            config.speed_sigma_mps, config.accel_sigma_mps2,
        ])

    def localize(self, scene: SceneState) -> Localization:
        n = (self.rng.standard_normal(5) * self.sigma).tolist()
        return Localization(
            t_s=float(scene.t_s),
            x_m=float(scene.x_m[0]) + n[0],
            y_m=float(scene.y_m[0]) + n[1],
            heading_rad=float(scene.heading_rad[0]) + n[2],
            speed_mps=float(scene.speed_mps[0]) + n[3],
            accel_mps2=float(scene.accel_mps2[0]) + n[4],
        )
