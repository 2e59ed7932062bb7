"""What planning computes as arrays, row by row: the predicted points in the ego's path, the
crossings' conflict regions and the speed profile. `RoutePlanner` (`planning.py`) fills them
for one run; the lockstep batch (`evoeye.ads.lockstep.planning`) for the rows of many runs at
once, each row exactly as alone.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Crossings(NamedTuple):
    """The obstacles crossing the path (m rows) and their conflict regions, as gap acceptance
    weighs them."""

    ids: np.ndarray  # (m,) track id
    d_in: np.ndarray  # (m,) from the ego's front to the conflict region along the route
    urgent: np.ndarray  # (m,) the ego can neither take the gap nor stop: brake hard
    conflict: np.ndarray  # (m,) the gap is not safe and the ego can stop before it


class InPath(NamedTuple):
    """The predicted points (n rows; the K-1 examined points) in the route frame and in the
    path, of predictions of which some enter it."""

    so: np.ndarray  # (n, K-1) route arc length
    in_path: np.ndarray  # (n, K-1)
    k_in: np.ndarray  # (n,) the first point in the path (0 if none)
    enters: np.ndarray  # (n,) some point is in the path
    aligned: np.ndarray  # (n,) moving along the route where it enters
    cross: np.ndarray  # (n,) entering, not aligned
    rear: np.ndarray  # (n,) route arc length of the rear now
    hl: np.ndarray  # (n, 1) half length, half width
    hw: np.ndarray
    cos_abs: np.ndarray  # (n, K-1) |cos|, |sin| of the heading relative to the route
    sin_abs: np.ndarray
    crossings: Crossings | None = None  # of the rows `cross`, when a batch computed them


def speed_profile(
    t: np.ndarray, v: float | np.ndarray, a: float | np.ndarray, t_end: float | np.ndarray,
    v_end: float | np.ndarray, s_e: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(speed, accel, route arc length) at times t (P,) of the plan from s_e at speed v that
    accelerates at a until t_end, then goes on at v_end. Elementwise: with the scalars as
    columns (B, 1), B plans (B, P) at once, each exactly as alone."""
    t_acc = np.minimum(t, t_end)  # (P,) time spent accelerating by t
    speed = v + a * t_acc
    accel = np.where(t < t_end, a, 0.0)
    s = (v + 0.5 * a * t_acc) * t_acc + v_end * (t - t_acc) + s_e  # route arc length
    return speed, accel, s
