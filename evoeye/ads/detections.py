"""The detection list the sensors hand the tracker: columnar, one row per field (DET_*)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# rows of the (DET_FIELDS, m) detection array
DET_X, DET_Y, DET_VX, DET_VY, DET_HEADING, DET_LENGTH, DET_WIDTH, DET_RANGE = range(8)
DET_VAR_POS, DET_VAR_VEL = 8, 9  # the variances of the position and velocity noise
DET_FIELDS = 10
VAR_FLOOR = 1e-4  # (0.01 m)², (0.01 m/s)²: no detector is exact


class Detections(NamedTuple):
    """One frame of detections; `actor_id` is ground truth, for tests only (trackers ignore it):
    the detected actor, the nearest actor of a merged segment, or a negative false-positive id."""

    actor_id: np.ndarray  # (m,)
    z: np.ndarray  # (DET_FIELDS, m)


def pack(
    pos: np.ndarray, vel: np.ndarray, heading_rad, length_m, width_m, range_m, var_pos, var_vel
) -> np.ndarray:
    """The (DET_FIELDS, m) detection array from complex positions and velocities (x + iy) (m,)
    and the other fields (arrays (m,) or scalars)."""
    m = len(pos)
    z = np.empty((DET_FIELDS, m))
    z[DET_X], z[DET_Y] = pos.real, pos.imag
    z[DET_VX], z[DET_VY] = vel.real, vel.imag
    z[DET_HEADING] = heading_rad
    z[DET_LENGTH] = length_m
    z[DET_WIDTH] = width_m
    z[DET_RANGE] = range_m
    z[DET_VAR_POS] = var_pos
    z[DET_VAR_VEL] = var_vel
    return z
