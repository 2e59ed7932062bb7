"""One decoded Autoware message → its values in evoeye's conventions (world frame, body centre).

Conventions converted here, once:
* base_link is the rear-axle centre: the body centre is `Vehicle.centre_ahead_m` ahead of it;
* an object's twist is in the object's own frame: rotated by its yaw into the world frame;
* yaw comes from the quaternion, which must be normalised (|q| within `QUAT_TOLERANCE` of 1;
  a small error is normalised away, a larger one rejects the bag);
* an object id (UUID) becomes an int64 track id (`TrackIds`), distinct within the run: a UUID
  whose last 8 bytes are zero (as evoeye exports its track ids) is its first 8 bytes,
  little-endian, signed, so evoeye's own ids survive an export and import unchanged; any other
  UUID is a 63-bit hash of its 16 bytes (a random UUID's first bytes alone would not fit the
  warehouse's INTEGER columns of old, nor stay distinct for structured UUIDs);
* the time of a message is its header stamp (its `stamp` field where it has no header), never
  the bag's receive time, except for a message type with no stamp at all (std_msgs/Bool).

Converters are picked by type name (`CONVERTERS`), the current and the `autoware_auto_*` names.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evoeye.sources.autoware.config import Vehicle

QUAT_TOLERANCE = 0.01
CLASS_NAMES = ("unknown", "car", "truck", "bus", "trailer", "motorcycle", "bicycle", "pedestrian")


class ConversionError(ValueError):
    """A message whose values cannot be evoeye's (the caller names the bag and topic)."""


def stamp_ns(msg: Any) -> int | None:
    """The message's own time, ns: header.stamp, or its stamp field; None if it has neither."""
    stamp = msg.header.stamp if hasattr(msg, "header") else getattr(msg, "stamp", None)
    return None if stamp is None else int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def yaw(q: Any) -> float:
    """Yaw, rad, of a geometry_msgs/Quaternion, checked to be normalised."""
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if not abs(norm - 1.0) <= QUAT_TOLERANCE:
        raise ConversionError(f"quaternion of norm {norm:.4g} is not normalised")
    x, y, z, w = q.x / norm, q.y / norm, q.z / norm, q.w / norm
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


RESERVED_IDS = (0, -1)  # the ego (actor 0) and "none"


def uuid_int(uuid: Any, salt: int = 0) -> int:
    """A unique_identifier_msgs/UUID as an int64: evoeye's own (its last 8 bytes zero) → its
    first 8 bytes, little-endian, signed; any other → a 63-bit hash of its bytes and `salt`."""
    raw = bytes(np.asarray(uuid.uuid, np.uint8))
    if raw[8:] == bytes(8) and salt == 0:
        return int.from_bytes(raw[:8], "little", signed=True)
    digest = hashlib.blake2b(raw, digest_size=8, salt=salt.to_bytes(16, "little")).digest()
    return int.from_bytes(digest, "little") >> 1


@dataclass
class TrackIds:
    """A run's object UUIDs → track ids, distinct within the run: a hashed id already taken by
    another UUID (or reserved) is hashed again with the next salt. Ids depend only on the
    UUIDs and the order they first appear in, so `import` and `watch` give the same."""

    by_uuid: dict[bytes, int] = field(default_factory=dict)
    taken: set[int] = field(default_factory=set)

    def __call__(self, uuid: Any) -> int:
        raw = bytes(np.asarray(uuid.uuid, np.uint8))
        if raw in self.by_uuid:
            return self.by_uuid[raw]
        track, salt = uuid_int(uuid), 0
        own = raw[8:] == bytes(8)  # evoeye's ids, -1 and 0 included, are kept as they are
        while track in self.taken or (not own and track in RESERVED_IDS):
            salt += 1
            own = False
            track = uuid_int(uuid, salt)
        self.by_uuid[raw] = track
        self.taken.add(track)
        return track


@dataclass(frozen=True)
class Context:
    """What a converter needs beside the message: the vehicle and the run's track ids."""

    vehicle: Vehicle = field(default_factory=Vehicle)
    ids: TrackIds = field(default_factory=TrackIds)


@dataclass(frozen=True)
class Ego:
    """The ego's body-centre state from an Odometry."""

    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    accel_mps2: float | None = None  # a pose that carries it (Apollo's); else another topic's


def odometry(msg: Any, ctx: Context) -> Ego:
    pose = msg.pose.pose
    h = yaw(pose.orientation)
    ahead = ctx.vehicle.centre_ahead_m
    return Ego(pose.position.x + ahead * math.cos(h), pose.position.y + ahead * math.sin(h), h,
               float(msg.twist.twist.linear.x))


def acceleration(msg: Any, ctx: Context) -> float:
    return float(msg.accel.accel.linear.x)


def _class_name(classification: list[Any]) -> str:
    if not classification:
        return "unknown"
    best = max(classification, key=lambda c: c.probability)
    return CLASS_NAMES[best.label] if best.label < len(CLASS_NAMES) else "unknown"


def objects(msg: Any, ctx: Context) -> dict[str, Any]:
    """TrackedObjects → the columns of evoeye.Obstacles (without t_s)."""
    rows = []
    for o in msg.objects:
        kin = o.kinematics
        pose = kin.pose_with_covariance.pose
        h = yaw(pose.orientation)
        v = kin.twist_with_covariance.twist.linear  # object frame: x forward, y left
        c, s = math.cos(h), math.sin(h)
        rows.append((ctx.ids(o.object_id), _class_name(o.classification), pose.position.x,
                     pose.position.y, h, c * v.x - s * v.y, s * v.x + c * v.y,
                     o.shape.dimensions.x, o.shape.dimensions.y, o.existence_probability))
    names = ("track_id", "obj_class", "x_m", "y_m", "heading_rad", "vx_mps", "vy_mps",
             "length_m", "width_m", "confidence")
    cols = list(zip(*rows, strict=True)) if rows else [()] * len(names)
    return {n: list(col) for n, col in zip(names, cols, strict=True)}


@dataclass(frozen=True)
class PredictedPath:
    confidence: float
    t_s: np.ndarray  # (m,) time of each pose after the message stamp, s (path[0] at 0)
    xy_m: np.ndarray  # (m, 2)


@dataclass(frozen=True)
class PredictedObject:
    track_id: int
    length_m: float
    width_m: float
    paths: tuple[PredictedPath, ...]  # most confident first


def predicted(msg: Any, ctx: Context) -> list[PredictedObject]:
    out = []
    for o in msg.objects:
        paths = []
        for p in o.kinematics.predicted_paths:
            step_s = p.time_step.sec + p.time_step.nanosec * 1e-9
            if len(p.path) and not step_s > 0.0:
                raise ConversionError(f"a predicted path has time_step {step_s} s")
            xy = np.array([(q.position.x, q.position.y) for q in p.path], np.float64)
            paths.append(PredictedPath(float(p.confidence), np.arange(len(p.path)) * step_s,
                                       xy.reshape(-1, 2)))
        paths.sort(key=lambda p: -p.confidence)  # stable: equal confidences keep their order
        out.append(PredictedObject(ctx.ids(o.object_id), float(o.shape.dimensions.x),
                                   float(o.shape.dimensions.y), tuple(paths)))
    return out


@dataclass(frozen=True)
class Trajectory:
    t_s: np.ndarray  # (P,) time_from_start, s, increasing
    x_m: np.ndarray
    y_m: np.ndarray
    heading_rad: np.ndarray  # unwrapped, so that it interpolates
    speed_mps: np.ndarray
    accel_mps2: np.ndarray
    times_recovered: bool  # the times were all zero and come from arc length over speed
    # a stack whose trajectory message carries the decision (Apollo's DecisionResult):
    # (decision, target speed m/s or None, leader track id); None: from the factor topics
    decision: tuple[str, float | None, int] | None = None


def _times_from_arc_length(x: np.ndarray, y: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Point times of a path whose time_from_start is all zero: ds over the mean speed."""
    ds = np.hypot(np.diff(x), np.diff(y))
    v_mid = 0.5 * (np.abs(v[1:]) + np.abs(v[:-1]))
    if np.any((ds > 1e-6) & (v_mid < 1e-3)):
        raise ConversionError("trajectory times are all zero and its speeds cannot give them "
                              "(a stretch at zero speed)")
    dt = np.divide(ds, v_mid, out=np.zeros_like(ds), where=v_mid >= 1e-3)
    return np.concatenate(([0.0], np.cumsum(dt)))


def trajectory(msg: Any, ctx: Context) -> Trajectory:
    pts = msg.points
    if not pts:
        raise ConversionError("trajectory has no points")
    t = np.array([p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in pts])
    x = np.array([p.pose.position.x for p in pts])
    y = np.array([p.pose.position.y for p in pts])
    h = np.unwrap([yaw(p.pose.orientation) for p in pts])
    v = np.array([p.longitudinal_velocity_mps for p in pts], np.float64)
    a = np.array([p.acceleration_mps2 for p in pts], np.float64)
    recovered = len(pts) > 1 and not np.any(t)
    if recovered:
        t = _times_from_arc_length(x, y, v)
    elif np.any(np.diff(t) <= 0.0):
        i = int(np.flatnonzero(np.diff(t) <= 0.0)[0])
        raise ConversionError(f"trajectory times are not increasing (point {i + 1} at "
                              f"{t[i + 1]:.3f} s after {t[i]:.3f} s)")
    ahead = ctx.vehicle.centre_ahead_m  # trajectory poses are base_link poses too
    return Trajectory(t, x + ahead * np.cos(h), y + ahead * np.sin(h), h, v, a, recovered)


def control(msg: Any, ctx: Context) -> tuple[float, float]:
    """(steering_rad, accel_cmd_mps2) of a Control (or AckermannControlCommand)."""
    return float(msg.lateral.steering_tire_angle), float(msg.longitudinal.acceleration)


def factor(msg: Any, ctx: Context) -> int | None:
    """None if the PlanningFactorArray has no factor; else the object the first one is about
    (its first OBJECT safety factor's id), -1 if none."""
    if not msg.factors:
        return None
    for s in msg.factors[0].safety_factors.factors:
        if s.type == 2:  # SafetyFactor.OBJECT
            return ctx.ids(s.object_id)
    return -1


def mrm_state(msg: Any, ctx: Context) -> bool:
    """True while a minimum-risk manoeuvre operates (MrmState.MRM_OPERATING)."""
    return int(msg.state) == 2


def velocity_limit(msg: Any, ctx: Context) -> float:
    return float(msg.max_velocity)


def collision(msg: Any, ctx: Context) -> bool:
    return bool(msg.data)


Converter = Callable[[Any, Context], Any]
# role → {type name → converter}: the current names and the pre-2024 autoware_auto_* names
_BY_ROLE: dict[str, dict[str, Converter]] = {
    "odometry": {"nav_msgs/msg/Odometry": odometry},
    "ground_truth_ego": {"nav_msgs/msg/Odometry": odometry},
    "acceleration": {"geometry_msgs/msg/AccelWithCovarianceStamped": acceleration},
    "objects": {"autoware_perception_msgs/msg/TrackedObjects": objects,
                "autoware_auto_perception_msgs/msg/TrackedObjects": objects},
    "ground_truth_objects": {"autoware_perception_msgs/msg/TrackedObjects": objects,
                             "autoware_auto_perception_msgs/msg/TrackedObjects": objects},
    "predicted": {"autoware_perception_msgs/msg/PredictedObjects": predicted,
                  "autoware_auto_perception_msgs/msg/PredictedObjects": predicted},
    "trajectory": {"autoware_planning_msgs/msg/Trajectory": trajectory,
                   "autoware_auto_planning_msgs/msg/Trajectory": trajectory},
    "control": {"autoware_control_msgs/msg/Control": control,
                "autoware_auto_control_msgs/msg/AckermannControlCommand": control},
    "factor": {"autoware_internal_planning_msgs/msg/PlanningFactorArray": factor,
               "tier4_planning_msgs/msg/PlanningFactorArray": factor},
    "mrm_state": {"autoware_adapi_v1_msgs/msg/MrmState": mrm_state},
    "velocity_limit": {"autoware_internal_planning_msgs/msg/VelocityLimit": velocity_limit,
                       "tier4_planning_msgs/msg/VelocityLimit": velocity_limit},
    "collision": {"std_msgs/msg/Bool": collision},
}


def converter(role: str, msgtype: str) -> Converter:
    """The converter of a role's message of type `msgtype`; ConversionError if it has none."""
    known = _BY_ROLE[role]
    if msgtype not in known:
        raise ConversionError(f"unknown message type {msgtype} for {role} (known: "
                              f"{', '.join(sorted(known))})")
    return known[msgtype]
