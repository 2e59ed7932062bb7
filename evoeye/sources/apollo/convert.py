"""One decoded Apollo message → its values in evoeye's conventions, as the Autoware converters
give them (`evoeye.sources.autoware.convert`), so the same frame assembler takes both.

Apollo's conventions, converted here once (docs/apollo.md):
* a message's time is `header.timestamp_sec` (float seconds, taken to the microsecond);
* the localization pose and the planned trajectory points are of the vehicle reference point,
  the rear-axle centre: the body centre is `Vehicle.centre_ahead_m` ahead along the heading;
  `pose.heading` is the heading (the quaternion is the IMU's, a quarter turn off);
* an obstacle's `position` is its box centre and its `velocity` is in the world frame; its box
  is `length` × `width` along `theta`, or, where those are unset, the extent of its polygon;
* obstacle ids are int32: kept, but for 0 (evoeye's ego) and −1 (none), moved past int32;
* control: `steering_target` is a percentage of the steering range
  (`ApolloVehicle.max_steer_rad`), `acceleration` the commanded m/s².
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from evoeye.sources.autoware.config import Vehicle
from evoeye.sources.autoware.convert import (
    Context,
    ConversionError,
    Ego,
    PredictedObject,
    PredictedPath,
    Trajectory,
)

# obj_class ⇄ (PerceptionObstacle.Type, SubType); the first of a class is what export writes
CLASSES = (("car", 5, 3), ("car", 5, 4), ("truck", 5, 5), ("bus", 5, 6), ("trailer", 5, 13),
           ("motorcycle", 4, 8), ("bicycle", 4, 7), ("pedestrian", 3, 10), ("car", 5, 0),
           ("bicycle", 4, 0), ("pedestrian", 3, 0), ("unknown", 0, 0))
MOVED_IDS = {0: 2**31, -1: 2**31 + 1}  # Apollo ids evoeye reserves, moved past int32
DECISIONS = {"follow": "follow", "yield": "yield", "stop": "yield", "overtake": "proceed"}


@dataclass(frozen=True)
class ApolloVehicle(Vehicle):
    """The ego's box, command scale and steering range (Apollo's vehicle_param)."""

    max_steer_rad: float = 0.5  # road-wheel angle at steering_target = 100 %


def stamp_ns(msg: Any) -> int | None:
    """header.timestamp_sec in ns, to the microsecond (a float of epoch seconds is ~0.2 µs
    fine); None if the message has no header time."""
    t = msg.header.timestamp_sec if msg.HasField("header") else 0.0
    return round(t * 1e6) * 1000 if t else None


def track_id(apollo_id: int) -> int:
    return MOVED_IDS.get(int(apollo_id), int(apollo_id))


def _class(o: Any) -> str:
    for name, kind, sub in CLASSES:
        if o.type == kind and (o.sub_type == sub or sub == 0):
            return name
    return "unknown"


def _box(o: Any) -> tuple[float, float, float, float]:
    """(x, y, length, width) of an obstacle: its box, or its polygon's extent along theta."""
    if o.length > 0.0 and o.width > 0.0 or not o.polygon_point:
        return o.position.x, o.position.y, o.length, o.width
    c, s = math.cos(o.theta), math.sin(o.theta)
    pts = np.array([(p.x, p.y) for p in o.polygon_point])
    along, across = pts @ np.array([c, s]), pts @ np.array([-s, c])
    mid_a, mid_c = 0.5 * (along.min() + along.max()), 0.5 * (across.min() + across.max())
    return (c * mid_a - s * mid_c, s * mid_a + c * mid_c, float(np.ptp(along)),
            float(np.ptp(across)))


def _xy(msg: Any, name: str) -> tuple[float, float] | None:
    """(x, y) of a Point3D field, None if unset (Apollo's Point3D defaults to NaN)."""
    if not msg.HasField(name):
        return None
    p = getattr(msg, name)
    return (p.x, p.y) if math.isfinite(p.x) and math.isfinite(p.y) else None


def localization(msg: Any, ctx: Context) -> Ego:
    pose = msg.pose
    position, v = _xy(pose, "position"), _xy(pose, "linear_velocity")
    if position is None or v is None or not pose.HasField("heading"):
        raise ConversionError("a pose without position, heading or linear_velocity")
    h = pose.heading
    a = _xy(pose, "linear_acceleration")  # without it: the speed's finite difference
    ahead = ctx.vehicle.centre_ahead_m
    return Ego(position[0] + ahead * math.cos(h), position[1] + ahead * math.sin(h), h,
               v[0] * math.cos(h) + v[1] * math.sin(h),
               None if a is None else a[0] * math.cos(h) + a[1] * math.sin(h))


def obstacles(msg: Any, ctx: Context) -> dict[str, Any]:
    """PerceptionObstacles → the columns of evoeye.Obstacles (without t_s)."""
    rows = []
    for o in msg.perception_obstacle:
        x, y, length, width = _box(o)
        vx, vy = _xy(o, "velocity") or (0.0, 0.0)  # an obstacle without one: at rest
        rows.append((track_id(o.id), _class(o), x, y, o.theta, vx, vy, length, width,
                     o.confidence))
    names = ("track_id", "obj_class", "x_m", "y_m", "heading_rad", "vx_mps", "vy_mps",
             "length_m", "width_m", "confidence")
    cols = list(zip(*rows, strict=True)) if rows else [()] * len(names)
    return {n: list(col) for n, col in zip(names, cols, strict=True)}


def predictions(msg: Any, ctx: Context) -> list[PredictedObject]:
    out = []
    for p in msg.prediction_obstacle:
        paths = []
        for traj in p.trajectory:
            t = np.array([q.relative_time for q in traj.trajectory_point], np.float64)
            if np.any(np.diff(t) <= 0.0):
                raise ConversionError("prediction times are not increasing")
            xy = np.array([(q.path_point.x, q.path_point.y) for q in traj.trajectory_point])
            paths.append(PredictedPath(float(traj.probability), t, xy.reshape(-1, 2)))
        paths.sort(key=lambda q: -q.confidence)
        o = p.perception_obstacle
        out.append(PredictedObject(track_id(o.id), float(o.length), float(o.width),
                                   tuple(paths)))
    return out


def _decision(msg: Any) -> tuple[str, float | None, int]:
    """(decision, target speed or None, leader) from an ADCTrajectory's DecisionResult."""
    main = msg.decision.main_decision
    target = main.target_lane[0].speed_limit if len(main.target_lane) else None
    if msg.estop.is_estop or main.HasField("estop"):
        return "emergency_brake", target, -1
    for d in msg.decision.object_decision.decision:
        for kind in d.object_decision:
            tag = kind.WhichOneof("object_tag")
            if tag in DECISIONS:
                leader = -1 if d.perception_id == -1 else track_id(d.perception_id)
                return DECISIONS[tag], target, leader
    return "cruise", target, -1


def planning(msg: Any, ctx: Context) -> Trajectory:
    pts = msg.trajectory_point
    if not pts:
        raise ConversionError("trajectory has no points")
    t = np.array([p.relative_time for p in pts], np.float64)
    if np.any(np.diff(t) <= 0.0):
        i = int(np.flatnonzero(np.diff(t) <= 0.0)[0])
        raise ConversionError(f"trajectory times are not increasing (point {i + 1} at "
                              f"{t[i + 1]:.3f} s after {t[i]:.3f} s)")
    h = np.unwrap([p.path_point.theta for p in pts])
    x = np.array([p.path_point.x for p in pts])
    y = np.array([p.path_point.y for p in pts])
    ahead = ctx.vehicle.centre_ahead_m  # points of the rear-axle centre
    return Trajectory(t, x + ahead * np.cos(h), y + ahead * np.sin(h), h,
                      np.array([p.v for p in pts]), np.array([p.a for p in pts]), False,
                      _decision(msg))


def control(msg: Any, ctx: Context) -> tuple[float, float]:
    """(steering_rad, accel_cmd_mps2) of a ControlCommand."""
    max_steer = getattr(ctx.vehicle, "max_steer_rad", ApolloVehicle.max_steer_rad)
    return float(msg.steering_target) / 100.0 * max_steer, float(msg.acceleration)


Converter = Callable[[Any, Context], Any]
TYPES = {  # role → (Apollo message type, converter)
    "odometry": ("apollo.localization.LocalizationEstimate", localization),
    "ground_truth_ego": ("apollo.localization.LocalizationEstimate", localization),
    "objects": ("apollo.perception.PerceptionObstacles", obstacles),
    "ground_truth_objects": ("apollo.perception.PerceptionObstacles", obstacles),
    "predicted": ("apollo.prediction.PredictionObstacles", predictions),
    "trajectory": ("apollo.planning.ADCTrajectory", planning),
    "control": ("apollo.control.ControlCommand", control),
}


def converter(role: str, msgtype: str) -> Converter:
    """The converter of a role's message of type `msgtype`; ConversionError if it has none."""
    if role not in TYPES:
        raise ConversionError(f"no Apollo channel plays {role}")
    known, convert = TYPES[role]
    if msgtype != known:
        raise ConversionError(f"unknown message type {msgtype} for {role} (known: {known})")
    return convert
