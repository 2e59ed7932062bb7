"""The sensor model: which actors the ego's sensors detect, and how noisily.

Detections are made from the ground truth: limited by range and field of view, hidden by nearer
vehicles (angular shadowing), missed at random more often far away and when partly occluded, and
perturbed by noise that grows with range. Each detection carries the variances of its noise, as a
real detector reports its uncertainty; the tracker uses them as its measurement noise.
Detections are columnar: one row per field (DET_*), one column per detection.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from evoeye.ads.config import SensorConfig
from evoeye.scene import SceneState

TWO_PI = 2.0 * math.pi
# rows of the (DET_FIELDS, m) detection array
DET_X, DET_Y, DET_VX, DET_VY, DET_HEADING, DET_LENGTH, DET_WIDTH, DET_RANGE = range(8)
DET_VAR_POS, DET_VAR_VEL = 8, 9
VAR_FLOOR = 1e-4  # (0.01 m)², (0.01 m/s)²: no detector is exact
DET_FIELDS = 10


class Detections(NamedTuple):
    """One frame of detections; `actor_id` is ground truth, for tests only (trackers ignore it)."""

    actor_id: np.ndarray  # (m,)
    z: np.ndarray  # (DET_FIELDS, m)


def occluded_fraction(
    range_m: np.ndarray, bearing_rad: np.ndarray, half_width_rad: np.ndarray
) -> np.ndarray:
    """Fraction of each target's angular extent covered by nearer actors, in [0, 1]. (n,)

    Pairwise: target i's interval [b_i − a_i, b_i + a_i] against every nearer j's interval;
    overlaps are summed (an upper bound on their union) and capped at 1. Bearings are not
    wrapped, so pass them relative to the sensor heading: the seam is then straight behind.
    """
    lo = bearing_rad - half_width_rad
    hi = bearing_rad + half_width_rad
    overlap = np.minimum.outer(hi, hi) - np.maximum.outer(lo, lo)  # (n, n) target i, actor j
    overlap = np.where(np.greater.outer(range_m, range_m), overlap, 0.0)  # nearer actors only
    return np.minimum(np.add.reduce(np.maximum(overlap, 0.0), axis=1) / (hi - lo), 1.0)


class SensorModel:
    """Front (limited field of view) and surround sensors, fused into one detection list."""

    def __init__(self, config: SensorConfig, rng: np.random.Generator) -> None:
        c = config
        self.c = c
        self.rng = rng
        self._sigma_base = np.array([[c.pos_sigma_m], [c.pos_sigma_m], [c.vel_sigma_mps],
                                     [c.vel_sigma_mps], [c.heading_sigma_rad]])  # (5, 1)
        self._sigma_slope = np.array([[c.pos_sigma_per_m], [c.pos_sigma_per_m],
                                      [c.vel_sigma_per_m], [c.vel_sigma_per_m],
                                      [c.heading_sigma_per_m]])
        # detection probability near − drop·r², reaching detect_prob_far at the front range
        self._p_drop_per_m2 = (c.detect_prob_near - c.detect_prob_far) / c.front_range_m**2
        self._empty = Detections(np.zeros(0, dtype=np.int64), np.zeros((DET_FIELDS, 0)))

    def detect(self, scene: SceneState) -> Detections:
        """Detections of every actor but the ego (row 0) at scene.t_s."""
        c = self.c
        n = len(scene.actor_id) - 1
        # a fixed number of draws per frame, whatever is detected: the stream stays aligned
        u = self.rng.random(n)
        noise = self.rng.standard_normal((5, n))
        if n == 0:
            return self._empty
        x, y, h = scene.x_m, scene.y_m, scene.heading_rad
        dx, dy = x[1:] - x[0], y[1:] - y[0]
        r = np.hypot(dx, dy)  # (n,)
        b = np.arctan2(dy, dx)  # absolute bearing
        rel = np.remainder(b - (h[0] - math.pi), TWO_PI) - math.pi  # bearing from the ego heading
        phi = h[1:] - b  # target orientation relative to the line of sight
        length, width = scene.length_m[1:], scene.width_m[1:]
        extent = length * np.abs(np.sin(phi)) + width * np.abs(np.cos(phi))  # seen across
        occ = occluded_fraction(r, rel, np.arctan2(extent, r + r))
        # detection probability: falls with range and with occlusion (to 0 at
        # occluded_fraction_max); none out of range (the front range inside the field of view,
        # the surround range elsewhere)
        r_max = np.where(np.abs(rel) <= c.front_half_fov_rad, c.front_range_m, c.surround_range_m)
        p = (c.detect_prob_near - self._p_drop_per_m2 * (r * r)) * (
            1.0 - occ * (1.0 / c.occluded_fraction_max)
        )
        idx = ((u < p) & (r <= r_max)).nonzero()[0]
        if len(idx) == 0:
            return self._empty
        speed = scene.speed_mps[1:]
        truth = np.array((
            x[1:], y[1:], speed * np.cos(h[1:]), speed * np.sin(h[1:]), h[1:], length, width, r,
        ))[:, idx]  # (8, m)
        sigma = self._sigma_base + self._sigma_slope * truth[DET_RANGE]  # (5, m)
        truth[:5] += sigma * noise[:, idx]
        # the reported variances have a floor: a Kalman update with R = 0 and a fresh track's
        # singular covariance would divide by zero
        z = np.concatenate((truth, sigma[0:3:2] ** 2 + VAR_FLOOR))
        return Detections(scene.actor_id[1:][idx], z)
