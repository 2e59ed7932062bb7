"""Predicted paths and trajectories resampled by time onto the grids of evoeye's own ADS.

The frame features pick raw points by index (`FeatureSpec.pred_raw_index`, `plan_raw_index`),
so a foreign stack's points must first sit where evoeye's ADS puts its own: prediction point k
at the frame time + (k+1)·0.1 s (k < 30), plan point j at the frame time + j·0.1 s (j ≤ 40).
A held message is `age_s` old at the frame, so its point for frame time + τ is the one at τ +
age_s after its own stamp. Positions and speeds are linear in time between points, headings
too (unwrapped). The grid a message covered when it was fresh stays covered while it is held:
up to `age_s` past its last point, values go on along its last segment (a 4 s plan held 50 ms
still gives 41 points, as evoeye's ADS always sends — a point short would change the plan mask
the monitor was trained on). A grid time further out is left out (a shorter prediction or plan).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from evoeye.ads.config import PlanningConfig, PredictionConfig
from evoeye.ads.messages import PREDICTION_MODES
from evoeye.sources.autoware.convert import PredictedObject, Trajectory

_PRED, _PLAN = PredictionConfig(), PlanningConfig()
PRED_DT_S = _PRED.dt_s
PRED_GRID_S = (np.arange(int(round(_PRED.horizon_s / _PRED.dt_s))) + 1) * _PRED.dt_s  # (K,)
# the ADS's own expression (evoeye.ads.planning), so lossless imports give its very floats
PLAN_GRID_S = np.arange(int(round(_PLAN.horizon_s / _PLAN.dt_s)) + 1) * _PLAN.dt_s  # (P,)
EXTERNAL_MODEL = PREDICTION_MODES[-1]  # "external": a mode another stack predicted
TIME_SLACK_S = 1e-6  # a grid time this close past the last point still takes it


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


def plan_points(traj: Trajectory, age_s: float, origin: tuple[float, float]) -> dict[str, Any]:
    """A Trajectory held `age_s` old → the per-point columns of evoeye.PlannedTrajectory."""
    grid = _within(PLAN_GRID_S, traj.t_s, age_s)
    at = grid + age_s

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
