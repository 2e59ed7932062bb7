"""Autoware recordings as a real stack's recorder writes them, made without evoeye's exporter.

rosbags writes the messages, typed by ROS 2 Humble's definitions and the upstream
autoware_msgs files (schemas/external/autoware, checked byte for byte against upstream by
tests/sources/test_autoware_upstream.py), registered here directly. The drive: the ego
(evoeye's default vehicle, base_link at the rear axle) follows a lane at 10 m/s towards a
stopped car 45 m ahead, brakes late (at 3.5 s, 6 m/s²) and hits it at 5 m/s (at 4.3 s); a
second car drives 40 m ahead in the next lane at the ego's speed.
Every object has a random 16-byte UUID. Topics at Autoware's rates (odometry 50 Hz, tracked and
predicted objects and trajectory 10 Hz, control 30 Hz, ground truth 10 Hz), each with its own
phase; header stamps run ahead of the receive (bag) time by a clock offset less each topic's
latency. Positions are in a UTM-like map frame, the lane heading 0.4 rad.

    drive = Drive(seed=0)
    store = upstream_store()
    write_mcap(dest, drive.messages(store), store)       # definitions embedded
    write_humble_db3(dest, drive.messages(store), store)  # none: sqlite schema 3, metadata v5
"""

from __future__ import annotations

import math
import sqlite3
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

UPSTREAM = Path(__file__).resolve().parents[3] / "schemas" / "external" / "autoware"
T0_NS = 1_700_000_000_123_456_789  # the first stamp: a real epoch, not a whole second
CLOCK_OFFSET_NS = 250_000_000  # stamps ahead of bag time by this, less each topic's latency
ORIGIN = (81_234.5, 4_321_098.7)  # ego's rear axle at t = 0, map frame (UTM-like)
HEADING = 0.4  # rad, the lane
EGO = (5.0, 2.0, 1.0)  # length, width, rear overhang (evoeye's default vehicle)
TOPICS = {  # role → (topic, type, period ns, phase ns, latency ns)
    "odometry": ("/localization/kinematic_state", "nav_msgs/msg/Odometry",
                 20_000_000, 3_000_000, 2_000_000),
    "objects": ("/perception/object_recognition/tracking/objects",
                "autoware_perception_msgs/msg/TrackedObjects", 100_000_000, 17_000_000,
                30_000_000),
    "predicted": ("/perception/object_recognition/objects",
                  "autoware_perception_msgs/msg/PredictedObjects", 100_000_000, 37_000_000,
                  45_000_000),
    "trajectory": ("/planning/scenario_planning/trajectory",
                   "autoware_planning_msgs/msg/Trajectory", 100_000_000, 52_000_000,
                   60_000_000),
    "control": ("/control/command/control_cmd", "autoware_control_msgs/msg/Control",
                33_333_333, 11_000_000, 5_000_000),
    "ground_truth": ("/simulation/ground_truth/objects",
                     "autoware_perception_msgs/msg/TrackedObjects", 100_000_000, 7_000_000,
                     1_000_000),
}


def upstream_store() -> Any:
    """ROS 2 Humble's types and the upstream Autoware definitions."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for path in sorted(UPSTREAM.glob("*/msg/*.msg")):
        types.update(get_types_from_msg(path.read_text(), f"{path.parts[-3]}/msg/{path.stem}"))
    store.register(types)
    return store


@dataclass
class Drive:
    """The drive's kinematics (module doc); times in s from T0_NS."""

    seed: int = 0
    duration_s: float = 5.0
    speed_mps: float = 10.0
    brake_at_s: float = 3.5
    decel_mps2: float = 6.0
    lead_ahead_m: float = 45.75  # the stopped car's centre ahead of the ego's body centre
    lead_size: tuple[float, float] = (4.5, 1.8)
    uuids: list[bytes] = field(init=False)

    def __post_init__(self) -> None:
        rng = np.random.default_rng(self.seed)
        self.uuids = [rng.bytes(16), rng.bytes(16)]  # the stopped car, the car alongside

    @property
    def contact_s(self) -> float:
        """When the ego's front touches the stopped car's rear."""
        gap = self.lead_ahead_m - 0.5 * (EGO[0] + self.lead_size[0]) - self.speed_mps * \
            self.brake_at_s  # left at the braking point
        v, a = self.speed_mps, self.decel_mps2
        return self.brake_at_s + (v - math.sqrt(v * v - 2 * a * gap)) / a

    def ego(self, t: float) -> tuple[float, float, float]:
        """(distance along the lane, speed, acceleration) of the ego; it stops at contact."""
        t = min(t, self.contact_s)
        if t <= self.brake_at_s:
            return self.speed_mps * t, self.speed_mps, 0.0
        tb = t - self.brake_at_s
        v = self.speed_mps - self.decel_mps2 * tb
        s = self.speed_mps * self.brake_at_s + self.speed_mps * tb - 0.5 * self.decel_mps2 * tb ** 2
        return s, (0.0 if t >= self.contact_s else v), -self.decel_mps2

    def objects(self, t: float) -> list[tuple[bytes, float, float, float, float, float]]:
        """(uuid, along, across, speed, length, width) of each object, along and across the
        lane from the ego's rear axle at t = 0; centres."""
        centre0 = EGO[0] / 2 - EGO[2]
        return [(self.uuids[0], centre0 + self.lead_ahead_m, 0.0, 0.0, *self.lead_size),
                (self.uuids[1], centre0 + 40.0 + 10.0 * t, 3.5, 10.0, 4.6, 1.9)]

    # -- messages --------------------------------------------------------------------------

    def messages(self, store: Any) -> list[tuple[int, str, str, Any]]:
        """[(bag ns, topic, type, message)] in bag-time order."""
        out = []
        for role, (topic, msgtype, period, phase, latency) in TOPICS.items():
            stamp = T0_NS + phase
            while stamp <= T0_NS + round(self.duration_s * 1e9):
                msg = BUILD[role](self, store, (stamp - T0_NS) / 1e9, stamp)
                out.append((stamp - CLOCK_OFFSET_NS + latency, topic, msgtype, msg))
                stamp += period
        out.sort(key=lambda m: (m[0], m[1]))
        return out


def _time(store: Any, ns: int) -> Any:
    return store.types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)


def _duration(store: Any, s: float) -> Any:
    ns = round(s * 1e9)
    return store.types["builtin_interfaces/msg/Duration"](sec=ns // 10**9, nanosec=ns % 10**9)


def _header(store: Any, ns: int) -> Any:
    return store.types["std_msgs/msg/Header"](stamp=_time(store, ns), frame_id="map")


def _vec(store: Any, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
    return store.types["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def _pose(store: Any, along: float, across: float = 0.0, heading: float = HEADING) -> Any:
    """The pose `along` and `across` the lane from the ego's start (map frame)."""
    c, s = math.cos(HEADING), math.sin(HEADING)
    p = store.types["geometry_msgs/msg/Point"](x=ORIGIN[0] + c * along - s * across,
                                               y=ORIGIN[1] + s * along + c * across, z=0.0)
    q = store.types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(heading / 2),
                                                    w=math.cos(heading / 2))
    return store.types["geometry_msgs/msg/Pose"](position=p, orientation=q)


def _twist(store: Any, vx: float) -> Any:
    t = store.types["geometry_msgs/msg/Twist"](linear=_vec(store, vx), angular=_vec(store))
    return store.types["geometry_msgs/msg/TwistWithCovariance"](twist=t, covariance=np.zeros(36))


def _pose_cov(store: Any, pose: Any) -> Any:
    return store.types["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36))


def _accel_cov(store: Any) -> Any:
    a = store.types["geometry_msgs/msg/Accel"](linear=_vec(store), angular=_vec(store))
    return store.types["geometry_msgs/msg/AccelWithCovariance"](accel=a, covariance=np.zeros(36))


def _uuid(store: Any, raw: bytes) -> Any:
    return store.types["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(raw, np.uint8).copy())


def _shape(store: Any, length: float, width: float) -> Any:
    return store.types["autoware_perception_msgs/msg/Shape"](
        type=0, footprint=store.types["geometry_msgs/msg/Polygon"](points=[]),
        dimensions=_vec(store, length, width, 1.5))


def _class(store: Any) -> Any:
    return store.types["autoware_perception_msgs/msg/ObjectClassification"](label=1,
                                                                           probability=0.9)


def _odometry(self: Drive, store: Any, t: float, stamp: int) -> Any:
    s, v, _ = self.ego(t)
    return store.types["nav_msgs/msg/Odometry"](
        header=_header(store, stamp), child_frame_id="base_link",
        pose=_pose_cov(store, _pose(store, s)), twist=_twist(store, v))


def _tracked(self: Drive, store: Any, t: float, stamp: int) -> Any:
    objs = []
    for uuid, along, across, v, length, width in self.objects(t):
        kin = store.types["autoware_perception_msgs/msg/TrackedObjectKinematics"](
            pose_with_covariance=_pose_cov(store, _pose(store, along, across)),
            twist_with_covariance=_twist(store, v), acceleration_with_covariance=_accel_cov(store),
            orientation_availability=2, is_stationary=v == 0.0)
        objs.append(store.types["autoware_perception_msgs/msg/TrackedObject"](
            object_id=_uuid(store, uuid), existence_probability=0.95,
            classification=[_class(store)], kinematics=kin, shape=_shape(store, length, width)))
    return store.types["autoware_perception_msgs/msg/TrackedObjects"](
        header=_header(store, stamp), objects=objs)


def _predicted(self: Drive, store: Any, t: float, stamp: int) -> Any:
    objs = []
    for uuid, along, across, v, length, width in self.objects(t):
        paths = [store.types["autoware_perception_msgs/msg/PredictedPath"](
            path=[_pose(store, along + v * 0.5 * k, across + shift * k / 20) for k in range(21)],
            time_step=_duration(store, 0.5), confidence=conf)
            for conf, shift in ((0.7, 0.0), (0.3, -3.5 if across else 0.0))]
        kin = store.types["autoware_perception_msgs/msg/PredictedObjectKinematics"](
            initial_pose_with_covariance=_pose_cov(store, _pose(store, along, across)),
            initial_twist_with_covariance=_twist(store, v),
            initial_acceleration_with_covariance=_accel_cov(store), predicted_paths=paths)
        objs.append(store.types["autoware_perception_msgs/msg/PredictedObject"](
            object_id=_uuid(store, uuid), existence_probability=0.95,
            classification=[_class(store)], kinematics=kin, shape=_shape(store, length, width)))
    return store.types["autoware_perception_msgs/msg/PredictedObjects"](
        header=_header(store, stamp), objects=objs)


def _trajectory(self: Drive, store: Any, t: float, stamp: int) -> Any:
    """From 2 m behind the ego (Autoware's extract_behind_dist), 0.1 s apart, 5 s."""
    s0, v0, _ = self.ego(t)
    braking = t >= self.brake_at_s
    pts, s, v = [], s0 - 2.0, v0
    for k in range(51):
        pts.append(store.types["autoware_planning_msgs/msg/TrajectoryPoint"](
            time_from_start=_duration(store, 0.1 * k), pose=_pose(store, s),
            longitudinal_velocity_mps=v, lateral_velocity_mps=0.0,
            acceleration_mps2=-self.decel_mps2 if braking and v > 0 else 0.0,
            heading_rate_rps=0.0, front_wheel_angle_rad=0.0, rear_wheel_angle_rad=0.0))
        v_next = max(v - self.decel_mps2 * 0.1, 0.0) if braking else v
        s += 0.05 * (v + v_next)
        v = v_next
    return store.types["autoware_planning_msgs/msg/Trajectory"](header=_header(store, stamp),
                                                                points=pts)


def _control(self: Drive, store: Any, t: float, stamp: int) -> Any:
    _, v, _ = self.ego(t)
    accel = -8.0 if t >= self.brake_at_s else 0.0
    now = _time(store, stamp)
    lat = store.types["autoware_control_msgs/msg/Lateral"](
        stamp=now, control_time=now, steering_tire_angle=0.0, steering_tire_rotation_rate=0.0,
        is_defined_steering_tire_rotation_rate=True)
    lon = store.types["autoware_control_msgs/msg/Longitudinal"](
        stamp=now, control_time=now, velocity=v, acceleration=accel, jerk=0.0,
        is_defined_acceleration=True, is_defined_jerk=False)
    return store.types["autoware_control_msgs/msg/Control"](
        stamp=now, control_time=now, lateral=lat, longitudinal=lon)


BUILD = {"odometry": _odometry, "objects": _tracked, "predicted": _predicted,
         "trajectory": _trajectory, "control": _control,
         "ground_truth": _tracked}  # perception is the truth here; the label reads the latter


# -- storage ---------------------------------------------------------------------------------

def _write(dest: Path, messages: list, store: Any, version: int, plugin: Any) -> Path:
    from rosbags.rosbag2 import Writer

    with Writer(dest, version=version, storage_plugin=plugin) as writer:
        conns: dict[str, Any] = {}
        for ns, topic, msgtype, msg in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(conns[topic], ns, store.serialize_cdr(msg, msgtype))
    return dest


def write_mcap(dest: Path, messages: list, store: Any) -> Path:
    """A rosbag2 MCAP bag folder (definitions embedded, as `ros2 bag record -s mcap`)."""
    from rosbags.rosbag2 import StoragePlugin

    return _write(dest, messages, store, 9, StoragePlugin.MCAP)


def write_humble_db3(dest: Path, messages: list, store: Any) -> Path:
    """A rosbag2 `.db3` bag folder as ROS 2 Humble records it: sqlite schema 3 (no message
    definitions, no type hashes) and metadata version 5."""
    import yaml
    from rosbags.rosbag2 import StoragePlugin

    _write(dest, messages, store, 8, StoragePlugin.SQLITE3)
    with sqlite3.connect(next(dest.glob("*.db3"))) as con:
        con.executescript("DROP TABLE message_definitions;"
                          "ALTER TABLE topics DROP COLUMN type_description_hash;"
                          "UPDATE schema SET schema_version = 3, ros_distro = 'humble';")
    meta_path = dest / "metadata.yaml"
    meta = yaml.safe_load(meta_path.read_text())
    info = meta["rosbag2_bagfile_information"]
    info["version"] = 5
    for key in ("ros_distro", "custom_data"):
        info.pop(key, None)
    for topic in info["topics_with_message_count"]:
        topic["topic_metadata"].pop("type_description_hash", None)
    meta_path.write_text(yaml.safe_dump(meta, sort_keys=False))
    return dest
