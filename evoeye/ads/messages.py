"""The messages the ADS modules exchange, one per module per frame (the runtime observation M(x)).

Field names are the JSON field names of the channel schemas in `schemas/mcap/`; a contract test
keeps the two identical. Arrays are columnar (one array per field, one row per obstacle) so a
frame's message maps straight onto Arrow list columns in the warehouse.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from operator import attrgetter
from typing import Any

import numpy as np


class Message:
    """Mixin: the message as a dict of its fields (numpy arrays kept; orjson serialises them)."""

    __slots__ = ()

    def to_dict(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self.field_names()}

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        names = cls.__dict__.get("_field_names")
        if names is None:
            names = tuple(f.name for f in fields(cls))  # type: ignore[arg-type]
            type.__setattr__(cls, "_field_names", names)
        return names

    def field_values(self) -> tuple[Any, ...]:
        """The values of the fields, in `field_names` order."""
        cls = type(self)
        get = cls.__dict__.get("_field_getter")
        if get is None:
            names = cls.field_names()
            get = attrgetter(*names) if len(names) > 1 else lambda m: (getattr(m, names[0]),)
            type.__setattr__(cls, "_field_getter", get)
        return get(self)


@dataclass(slots=True)
class Localization(Message):
    """The ego's own state estimate."""

    t_s: float
    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    accel_mps2: float


@dataclass(slots=True)
class Obstacles(Message):
    """Tracked obstacles reported by perception (n rows)."""

    t_s: float
    track_id: np.ndarray  # (n,) int
    obj_class: list[str]  # (n,) e.g. "car"
    x_m: np.ndarray  # (n,) world frame
    y_m: np.ndarray
    heading_rad: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray
    length_m: np.ndarray
    width_m: np.ndarray
    confidence: np.ndarray  # (n,) in [0, 1]


@dataclass(slots=True)
class Predictions(Message):
    """Predicted future centre positions of every tracked obstacle over horizon_s, one row per
    (track, mode): the rows of a track are contiguous, most probable first, and their
    `mode_prob` sum to 1 (less the dropped improbable modes)."""

    t_s: float
    dt_s: float  # spacing of the K predicted points; point k is at t_s + (k+1)·dt_s
    track_id: np.ndarray  # (n,)
    model: list[str]  # (n,) one of PREDICTION_MODES
    mode_prob: np.ndarray  # (n,) probability of the mode
    length_m: np.ndarray  # (n,)
    width_m: np.ndarray  # (n,)
    x_m: np.ndarray  # (n, K)
    y_m: np.ndarray  # (n, K)


@dataclass(slots=True)
class PlannedTrajectory(Message):
    """The ego trajectory planning commits to, and why."""

    t_s: float
    decision: str  # one of PLANNING_DECISIONS
    target_speed_mps: float
    leader_track_id: int  # the obstacle being followed or yielded to, -1 if none
    t_rel_s: np.ndarray  # (P,) time of each point after t_s
    x_m: np.ndarray  # (P,)
    y_m: np.ndarray
    heading_rad: np.ndarray
    speed_mps: np.ndarray
    accel_mps2: np.ndarray


# constant velocity; along a lane (or one of its continuations); a lane change left or right;
# stopping at the end of a lane that gives way (the rule of the road)
# "external": a mode another stack predicted (an imported recording); never one of this ADS's
PREDICTION_MODES = ("cv", "lane", "left", "right", "yield", "external")
PLANNING_DECISIONS = ("cruise", "follow", "yield", "proceed", "emergency_brake")


@dataclass(slots=True)
class ControlCommand(Message):
    """Actuator command applied to the ego for the next frame."""

    t_s: float
    throttle: float  # [0, 1]
    brake: float  # [0, 1]
    steering_rad: float  # front-wheel angle
    accel_cmd_mps2: float  # the acceleration the command asks for


@dataclass(slots=True)
class FrameMessages:
    """All module outputs of one ADS frame."""

    localization: Localization
    obstacles: Obstacles
    predictions: Predictions
    plan: PlannedTrajectory
    control: ControlCommand

    def all_finite(self) -> bool:
        """False if any numeric field of any message is NaN or infinite (one vectorised check)."""
        arrays, scalars = [], []
        for msg in (self.localization, self.obstacles, self.predictions, self.plan, self.control):
            for value in msg.field_values():
                if isinstance(value, np.ndarray):
                    if value.dtype.kind == "f":
                        arrays.append(value.ravel())
                elif isinstance(value, float):
                    scalars.append(value)
        arrays.append(np.asarray(scalars))
        values = np.concatenate(arrays)
        return np.count_nonzero(np.isfinite(values)) == values.size
