"""False positives of the sensor set: short-lived clutter and persistent radar multipath ghosts.

* Clutter (spray, vegetation, road furniture): a Poisson number of static, small detections per
  frame at random places within the lidar's range. Each lives one frame, so the tracker's
  confirmation (M hits) rejects nearly all of them; a burst at one place can still confirm.
* Ghosts: a radar target beyond `ghost_min_range_m` is reflected by a guard-rail parallel to the
  ego at `ghost_rail_offset_m` on its side, and appears mirrored behind the rail with probability
  `ghost_prob` per frame — often enough to be confirmed and tracked like a real car.

Detections are in the sensor frame (x forward, y left, velocity relative to the ego), in the
layout of `evoeye.ads.detections`. A fixed number of uniforms is consumed per frame (`n_uniforms`
for clutter, and the sensor model draws one per actor for ghosts) so the random stream stays
aligned.
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from scipy.stats import poisson

from evoeye.ads.config import SensorConfig
from evoeye.ads.detections import (
    DET_FIELDS,
    DET_HEADING,
    DET_RANGE,
    DET_VY,
    DET_X,
    DET_Y,
    VAR_FLOOR,
    pack,
)

CLUTTER_ID = -1  # actor_id of a clutter detection
GHOST_ID = -2  # actor_id of a multipath ghost
CLUTTER_SIZE_M = 1.0  # clutter boxes are small


class FalsePositives:
    """Clutter and ghost detections for one frame, from uniforms drawn by the sensor model."""

    def __init__(self, config: SensorConfig) -> None:
        c = config
        self.c = c
        self.n_max = max(0, int(c.clutter_max_per_frame))
        self.n_uniforms = 1 + 2 * self.n_max  # count, then range and bearing per slot
        # inverse CDF of the (truncated) Poisson count: P(N ≤ k) for k = 0 … n_max − 1
        self._cdf = poisson.cdf(np.arange(self.n_max), c.clutter_rate_per_frame).tolist()
        self._none = (np.zeros(0, dtype=np.int64), np.zeros((DET_FIELDS, 0)))

    def detect(self, u: np.ndarray, ego_speed_mps: float) -> tuple[np.ndarray, np.ndarray]:
        """(actor ids, (DET_FIELDS, k) detections) of this frame's clutter from n_uniforms
        uniforms."""
        c = self.c
        k = bisect.bisect_right(self._cdf, float(u[0]))
        if k == 0:
            return self._none
        r = c.clutter_min_range_m + (c.lidar_range_m - c.clutter_min_range_m) * u[1:1 + k]
        bearing = (2.0 * u[1 + self.n_max:1 + self.n_max + k] - 1.0) * math.pi
        z = pack(
            r * np.exp(1j * bearing), np.full(k, -ego_speed_mps + 0j),  # static in the world
            0.0, CLUTTER_SIZE_M, CLUTTER_SIZE_M, r,
            (c.pos_sigma_m + c.pos_sigma_per_m * r) ** 2 + VAR_FLOOR,
            (c.vel_sigma_mps + c.vel_sigma_per_m * r) ** 2 + VAR_FLOOR,
        )
        return np.full(k, CLUTTER_ID, dtype=np.int64), z

    def ghosts(self, radar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(actor ids, (DET_FIELDS, k) detections) of the multipath ghosts of these radar
        detections (DET_FIELDS, m): the ones the sensor model drew to have one."""
        visible, z = self.mirror(radar)
        if np.count_nonzero(visible) < len(visible):
            z = z[:, visible]
        return np.full(z.shape[1], GHOST_ID, dtype=np.int64), z

    def mirror(self, radar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(visible mask, mirrored detections (DET_FIELDS, m)): each radar detection mirrored in
        the guard rail on its side, and whether the radar would see the mirror image.
        Elementwise per column, so the detections of many runs can share one call."""
        c = self.c
        z = radar.copy()
        rail = np.where(z[DET_Y] >= 0.0, c.ghost_rail_offset_m, -c.ghost_rail_offset_m)
        z[DET_Y] = 2.0 * rail - z[DET_Y]
        z[DET_VY] = -z[DET_VY]
        z[DET_HEADING] = -z[DET_HEADING]
        z[DET_RANGE] = np.hypot(z[DET_X], z[DET_Y])
        visible = (np.abs(np.arctan2(z[DET_Y], z[DET_X])) <= c.radar_half_fov_rad) & (
            z[DET_RANGE] <= c.radar_range_m)
        return visible, z
