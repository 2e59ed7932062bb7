"""Predicted paths and trajectories resampled by time onto the grids of evoeye's own ADS.

The frame features pick raw points by index (`FeatureSpec.pred_raw_index`, `plan_raw_index`),
so a foreign stack's points must first sit where evoeye's ADS puts its own: prediction point k
at the frame time + (k+1)·0.1 s (k < 30), plan point j at the frame time + j·0.1 s (j ≤ 40).
A held prediction is `age_s` old at the frame, so its point for frame time + τ is the one at
τ + age_s after its own stamp. Positions and speeds are linear in time between points, headings
too (unwrapped). The grid a message covered when it was fresh stays covered while it is held:
past its last point, values go on along its last segment (a 4 s plan held 50 ms still gives
41 points, as evoeye's ADS always sends — a point short would change the plan mask the monitor
was trained on). A grid time further out is left out (a shorter prediction or plan).

A trajectory is read from where the ego is on it (`ego_time_s`), not from its age. evoeye's ADS
re-plans every frame from the ego's projection onto its reference path: plan point 0 is level
with the ego (along the ego, within a millimetre; across, the ego's offset from the path).
Autoware's consumers (its controllers, its velocity smoother) likewise find the ego on a
trajectory by its nearest segment, and Autoware's trajectories start behind the ego (the
velocity smoother keeps `extract_behind_dist` of it). So a frame's plan starts at the time on
the trajectory nearest the ego's pose of that frame, and its points follow 0.1 s apart from
there: the path (the stack's geometry) stays where it is, only its time origin moves along it.
Read by its age instead, a 10 Hz trajectory held 50 ms starts where it expected the ego to be,
centimetres to decimetres off — an input evoeye's own plans never give.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from evoeye.ads.config import PlanningConfig, PredictionConfig
from evoeye.ads.messages import PREDICTION_MODES
from evoeye.sources.autoware.convert import Ego, PredictedObject, Trajectory

_PRED, _PLAN = PredictionConfig(), PlanningConfig()
PRED_DT_S = _PRED.dt_s
PRED_GRID_S = (np.arange(int(round(_PRED.horizon_s / _PRED.dt_s))) + 1) * _PRED.dt_s  # (K,)
# the ADS's own expression (evoeye.ads.planning), so lossless imports give its very floats
PLAN_GRID_S = np.arange(int(round(_PLAN.horizon_s / _PLAN.dt_s)) + 1) * _PLAN.dt_s  # (P,)
EXTERNAL_MODEL = PREDICTION_MODES[-1]  # "external": a mode another stack predicted
TIME_SLACK_S = 1e-6  # a grid time this close past the last point still takes it
EGO_YAW_LIMIT_RAD = math.radians(60.0)  # Autoware's ego_nearest_yaw_threshold (1.046 rad)
TIE_M = 1e-6  # segments this close to the ego's distance are equally near (a point dwelt at)


def _within(grid_s: np.ndarray, times_s: np.ndarray, age_s: float) -> np.ndarray:
    """The grid times the message covered when fresh: not past its last point (module doc)."""
    return grid_s[grid_s <= times_s[-1] + TIME_SLACK_S] if len(times_s) else grid_s[:0]


def _at(at: np.ndarray, times_s: np.ndarray, values: np.ndarray) -> np.ndarray:
    """`values` (one per time) at the times `at`, linear, and along the last segment past the
    last time."""
    out = np.interp(at, times_s, values)
    past = at > times_s[-1]
    if past.any() and len(times_s) > 1:
        slope = (values[-1] - values[-2]) / (times_s[-1] - times_s[-2])
        out[past] = values[-1] + slope * (at[past] - times_s[-1])
    return out


def predictions(objects: list[PredictedObject], age_s: float,
                origin: tuple[float, float]) -> dict[str, Any]:
    """PredictedObjects held `age_s` old → the columns of evoeye.Predictions (without t_s)."""
    cols: dict[str, list] = {k: [] for k in ("track_id", "model", "mode_prob", "length_m",
                                             "width_m", "x_m", "y_m")}
    for obj in objects:
        for path in obj.paths:
            grid = _within(PRED_GRID_S, path.t_s, age_s)
            if len(grid) == 0:
                continue  # nothing of this mode reaches the frame's first grid time
            at = grid + age_s
            cols["track_id"].append(obj.track_id)
            cols["model"].append(EXTERNAL_MODEL)
            cols["mode_prob"].append(path.confidence)
            cols["length_m"].append(obj.length_m)
            cols["width_m"].append(obj.width_m)
            cols["x_m"].append((_at(at, path.t_s, path.xy_m[:, 0]) - origin[0]).tolist())
            cols["y_m"].append((_at(at, path.t_s, path.xy_m[:, 1]) - origin[1]).tolist())
    return {"dt_s": PRED_DT_S, **cols}


def ego_time_s(traj: Trajectory, x_m: float, y_m: float, heading_rad: float,
               age_s: float) -> float:
    """The time on `traj` (from its stamp) nearest the ego's pose (module doc).

    The ego's projection onto each segment (clipped to it), preferring segments heading within
    EGO_YAW_LIMIT_RAD of the ego (any if none does); the nearest wins. Where the trajectory
    dwells (a stop: its points at one place over a while), that place is as near at every time,
    and the time is the one closest to `age_s`, as the message's age places the ego."""
    t = traj.t_s
    if len(t) < 2:
        return age_s
    x, y, h = traj.x_m, traj.y_m, traj.heading_rad
    dx, dy = np.diff(x), np.diff(y)  # (P-1,) segments
    seg2 = dx * dx + dy * dy
    moving = seg2 > 0.0
    u = np.clip(((x_m - x[:-1]) * dx + (y_m - y[:-1]) * dy)
                / np.where(moving, seg2, 1.0), 0.0, 1.0)
    times = np.where(moving, t[:-1] + u * np.diff(t), np.clip(age_s, t[:-1], t[1:]))
    dist_m = np.hypot(x[:-1] + u * dx - x_m, y[:-1] + u * dy - y_m)
    dyaw = np.angle(np.exp(1j * (h[:-1] + u * np.diff(h) - heading_rad)))
    ahead = np.abs(dyaw) <= EGO_YAW_LIMIT_RAD
    dist_m = np.where(ahead, dist_m, np.inf) if ahead.any() else dist_m
    near = dist_m <= dist_m.min() + TIE_M
    return float(times[near][np.argmin(np.abs(times[near] - age_s))])


def plan_points(traj: Trajectory, ego: Ego, age_s: float,
                origin: tuple[float, float]) -> dict[str, Any]:
    """A Trajectory held `age_s` old → the per-point columns of evoeye.PlannedTrajectory, its
    point 0 where `ego` (the frame's pose, map frame) is on it."""
    grid = _within(PLAN_GRID_S, traj.t_s, age_s)
    at = grid + ego_time_s(traj, ego.x_m, ego.y_m, ego.heading_rad, age_s)

    def at_grid(values: np.ndarray) -> list[float]:
        return _at(at, traj.t_s, values).tolist()

    h = _at(at, traj.t_s, traj.heading_rad)
    return {
        "t_rel_s": grid.tolist(),
        "x_m": (_at(at, traj.t_s, traj.x_m) - origin[0]).tolist(),
        "y_m": (_at(at, traj.t_s, traj.y_m) - origin[1]).tolist(),
        "heading_rad": np.arctan2(np.sin(h), np.cos(h)).tolist(),
        "speed_mps": at_grid(traj.speed_mps),
        "accel_mps2": at_grid(traj.accel_mps2),
    }
