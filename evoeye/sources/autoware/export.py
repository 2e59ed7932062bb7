"""An evoeye run log → an Autoware-typed rosbag2 MCAP bag, with the stack's conventions.

The messages are those an Autoware stack would record (`config.Topics`, standard type names):
odometry of base_link (the rear-axle centre), object twists in the object's frame, UUIDs,
predicted paths that start at t = 0, trajectories with `time_from_start`, a `Control`, planning
factors for the decision, a velocity limit for the target speed and an MRM state for an
emergency brake. The ground truth goes on the simulation topics (true objects, true ego pose;
optionally the collision event), so an import can label the run, and the run's identity on the
rosbag2 custom data `evoeye.run`. The definitions are embedded: any ROS 2 tool reads the bag.

Rates (`RATES`): `lossless` publishes every topic on the 20 Hz frame clock (an import gives the
native frames back); `realistic` publishes as Autoware does — odometry 50 Hz (between two frames,
linear in time), tracked and predicted objects, trajectory and planning at 10 Hz (every other
frame), control 33 Hz (the command in force) — and ground truth at 20 Hz.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from evoeye.log import TOPICS, read_run
from evoeye.sources.autoware.bag import IDENTITY, OPTIONAL_IDENTITY, RUN_KEY
from evoeye.sources.autoware.config import Mapping
from evoeye.sources.autoware.convert import CLASS_NAMES
from evoeye.sources.autoware.typestore import typestore

FRAME_NS = 50_000_000
BEHAVIOR = {"yield": 3, "follow": 2, "proceed": 1}  # PlanningFactor STOP, SLOW_DOWN, NONE


@dataclass(frozen=True)
class Rates:
    """Publish period of each kind of topic, ns (a multiple of none in particular)."""

    odometry_ns: int
    objects_ns: int
    planning_ns: int
    control_ns: int


RATES = {
    "lossless": Rates(FRAME_NS, FRAME_NS, FRAME_NS, FRAME_NS),
    "realistic": Rates(20_000_000, 100_000_000, 100_000_000, 30_000_000),
}


class _Build:
    """Message constructors over one typestore."""

    def __init__(self) -> None:
        self.store = typestore()
        self.t = self.store.types

    def time(self, t_ns: int) -> Any:
        return self.t["builtin_interfaces/msg/Time"](sec=t_ns // 1_000_000_000,
                                                     nanosec=t_ns % 1_000_000_000)

    def duration(self, t_s: float) -> Any:
        ns = round(t_s * 1e9)
        return self.t["builtin_interfaces/msg/Duration"](sec=ns // 1_000_000_000,
                                                         nanosec=ns % 1_000_000_000)

    def header(self, t_ns: int) -> Any:
        return self.t["std_msgs/msg/Header"](stamp=self.time(t_ns), frame_id="map")

    def vec(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
        return self.t["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def pose(self, x: float, y: float, heading: float) -> Any:
        q = self.t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(0.5 * heading),
                                                   w=math.cos(0.5 * heading))
        p = self.t["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0)
        return self.t["geometry_msgs/msg/Pose"](position=p, orientation=q)

    def uuid(self, track_id: int) -> Any:
        raw = int(track_id).to_bytes(8, "little", signed=True) + bytes(8)
        return self.t["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(raw, np.uint8).copy())

    def twist(self, vx: float, vy: float) -> Any:
        t = self.t["geometry_msgs/msg/Twist"](linear=self.vec(vx, vy), angular=self.vec())
        return self.t["geometry_msgs/msg/TwistWithCovariance"](twist=t, covariance=np.zeros(36))

    def pose_cov(self, x: float, y: float, h: float) -> Any:
        return self.t["geometry_msgs/msg/PoseWithCovariance"](pose=self.pose(x, y, h),
                                                              covariance=np.zeros(36))

    def accel_cov(self, ax: float = 0.0) -> Any:
        a = self.t["geometry_msgs/msg/Accel"](linear=self.vec(ax), angular=self.vec())
        return self.t["geometry_msgs/msg/AccelWithCovariance"](accel=a, covariance=np.zeros(36))

    def shape(self, length: float, width: float) -> Any:
        footprint = self.t["geometry_msgs/msg/Polygon"](points=[])
        return self.t["autoware_perception_msgs/msg/Shape"](
            type=0, footprint=footprint, dimensions=self.vec(length, width, 1.5))


def _interp_loc(a: dict, b: dict, w: float) -> dict:
    """Localization a fraction `w` of the way from message a to message b."""
    dh = math.remainder(b["heading_rad"] - a["heading_rad"], math.tau)
    return {k: (a[k] + dh * w if k == "heading_rad" else a[k] + (b[k] - a[k]) * w)
            for k in ("x_m", "y_m", "heading_rad", "speed_mps", "accel_mps2")}


class Exporter:
    """Builds the Autoware messages of one run's frames."""

    def __init__(self, mapping: Mapping) -> None:
        self.b = _Build()
        self.m = mapping
        self.ahead = mapping.vehicle.centre_ahead_m

    def odometry(self, t_ns: int, x: float, y: float, h: float, speed: float) -> Any:
        b = self.b
        x, y = x - self.ahead * math.cos(h), y - self.ahead * math.sin(h)
        return b.t["nav_msgs/msg/Odometry"](header=b.header(t_ns), child_frame_id="base_link",
                                           pose=b.pose_cov(x, y, h), twist=b.twist(speed, 0.0))

    def acceleration(self, t_ns: int, ax: float) -> Any:
        return self.b.t["geometry_msgs/msg/AccelWithCovarianceStamped"](
            header=self.b.header(t_ns), accel=self.b.accel_cov(ax))

    def tracked(self, t_ns: int, ids: list, classes: list, x: list, y: list, h: list, vx: list,
                vy: list, length: list, width: list, confidence: list) -> Any:
        b, objs = self.b, []
        for i in range(len(ids)):
            c, s = math.cos(h[i]), math.sin(h[i])
            kin = b.t["autoware_perception_msgs/msg/TrackedObjectKinematics"](
                pose_with_covariance=b.pose_cov(x[i], y[i], h[i]),
                twist_with_covariance=b.twist(c * vx[i] + s * vy[i], -s * vx[i] + c * vy[i]),
                acceleration_with_covariance=b.accel_cov(), orientation_availability=2,
                is_stationary=False)
            label = CLASS_NAMES.index(classes[i]) if classes[i] in CLASS_NAMES else 0
            cls = b.t["autoware_perception_msgs/msg/ObjectClassification"](label=label,
                                                                         probability=1.0)
            objs.append(b.t["autoware_perception_msgs/msg/TrackedObject"](
                object_id=b.uuid(ids[i]), existence_probability=float(confidence[i]),
                classification=[cls], kinematics=kin, shape=b.shape(length[i], width[i])))
        return b.t["autoware_perception_msgs/msg/TrackedObjects"](header=b.header(t_ns),
                                                                   objects=objs)

    def obstacles(self, t_ns: int, o: dict) -> Any:
        return self.tracked(t_ns, o["track_id"], o["obj_class"], o["x_m"], o["y_m"],
                            o["heading_rad"], o["vx_mps"], o["vy_mps"], o["length_m"],
                            o["width_m"], o["confidence"])

    def truth_objects(self, t_ns: int, g: dict) -> Any:
        n = len(g["actor_id"])
        pick = [g[k][1:] for k in ("actor_id", "x_m", "y_m", "heading_rad", "vx_mps", "vy_mps",
                                   "length_m", "width_m")]
        ids, x, y, h, vx, vy, length, width = pick
        return self.tracked(t_ns, ids, ["car"] * (n - 1), x, y, h, vx, vy, length, width,
                            [1.0] * (n - 1))

    def predicted(self, t_ns: int, p: dict, o: dict) -> Any:
        b = self.b
        now = {tid: (x, y, h) for tid, x, y, h in zip(o["track_id"], o["x_m"], o["y_m"],
                                                      o["heading_rad"], strict=True)}
        rows: dict[int, list[int]] = {}
        for i, tid in enumerate(p["track_id"]):
            rows.setdefault(tid, []).append(i)
        objs = []
        for tid, idx in rows.items():
            first = idx[0]
            x0, y0, h0 = now.get(tid, (p["x_m"][first][0], p["y_m"][first][0], 0.0))
            paths = []
            for i in idx:
                xs, ys = [x0, *p["x_m"][i]], [y0, *p["y_m"][i]]
                hs = [h0] + [math.atan2(ys[k + 1] - ys[k], xs[k + 1] - xs[k])
                             for k in range(len(xs) - 1)]
                paths.append(b.t["autoware_perception_msgs/msg/PredictedPath"](
                    path=[b.pose(*xyh) for xyh in zip(xs, ys, hs, strict=True)],
                    time_step=b.duration(p["dt_s"]), confidence=float(p["mode_prob"][i])))
            kin = b.t["autoware_perception_msgs/msg/PredictedObjectKinematics"](
                initial_pose_with_covariance=b.pose_cov(x0, y0, h0),
                initial_twist_with_covariance=b.twist(0.0, 0.0),
                initial_acceleration_with_covariance=b.accel_cov(), predicted_paths=paths)
            cls = b.t["autoware_perception_msgs/msg/ObjectClassification"](label=1,
                                                                         probability=1.0)
            objs.append(b.t["autoware_perception_msgs/msg/PredictedObject"](
                object_id=b.uuid(tid), existence_probability=1.0, classification=[cls],
                kinematics=kin, shape=b.shape(p["length_m"][first], p["width_m"][first])))
        return b.t["autoware_perception_msgs/msg/PredictedObjects"](header=b.header(t_ns),
                                                                     objects=objs)

    def trajectory(self, t_ns: int, p: dict) -> Any:
        b, a = self.b, self.ahead
        pts = [b.t["autoware_planning_msgs/msg/TrajectoryPoint"](
            time_from_start=b.duration(t), pose=b.pose(x - a * math.cos(h), y - a * math.sin(h), h),
            longitudinal_velocity_mps=float(v), lateral_velocity_mps=0.0,
            acceleration_mps2=float(acc), heading_rate_rps=0.0, front_wheel_angle_rad=0.0,
            rear_wheel_angle_rad=0.0)
            for t, x, y, h, v, acc in zip(p["t_rel_s"], p["x_m"], p["y_m"], p["heading_rad"],
                                          p["speed_mps"], p["accel_mps2"], strict=True)]
        return b.t["autoware_planning_msgs/msg/Trajectory"](header=b.header(t_ns), points=pts)

    def control(self, t_ns: int, c: dict, speed: float) -> Any:
        b, now = self.b, self.b.time(t_ns)  # control_time: the command is meant at once
        lat = b.t["autoware_control_msgs/msg/Lateral"](
            stamp=now, control_time=now, steering_tire_angle=float(c["steering_rad"]),
            steering_tire_rotation_rate=0.0, is_defined_steering_tire_rotation_rate=False)
        lon = b.t["autoware_control_msgs/msg/Longitudinal"](
            stamp=now, control_time=now, velocity=float(speed),
            acceleration=float(c["accel_cmd_mps2"]), jerk=0.0, is_defined_acceleration=True,
            is_defined_jerk=False)
        return b.t["autoware_control_msgs/msg/Control"](stamp=now, control_time=now,
                                                        lateral=lat, longitudinal=lon)

    def factors(self, t_ns: int, topic: str, meant: str, plan: dict) -> Any:
        b, t = self.b, self.b.t
        factors = []
        if plan["decision"] == meant:
            safety = t["autoware_internal_planning_msgs/msg/SafetyFactor"](
                type=2, object_id=b.uuid(plan["leader_track_id"]),
                predicted_path=t["autoware_perception_msgs/msg/PredictedPath"](
                    path=[], time_step=b.duration(0.0), confidence=0.0),
                ttc_begin=0.0, ttc_end=0.0, points=[], is_safe=False)
            arr = t["autoware_internal_planning_msgs/msg/SafetyFactorArray"](
                header=b.header(t_ns), factors=[safety], is_safe=False, detail="")
            factors.append(t["autoware_internal_planning_msgs/msg/PlanningFactor"](
                module=topic.rsplit("/", 1)[-1], is_driving_forward=True, control_points=[],
                behavior=BEHAVIOR.get(meant, 0), detail="", safety_factors=arr))
        return t["autoware_internal_planning_msgs/msg/PlanningFactorArray"](
            header=b.header(t_ns), factors=factors)

    def velocity_limit(self, t_ns: int, plan: dict) -> Any:
        t = self.b.t
        c = t["autoware_internal_planning_msgs/msg/VelocityLimitConstraints"](
            max_acceleration=0.0, min_acceleration=0.0, max_jerk=0.0, min_jerk=0.0)
        return t["autoware_internal_planning_msgs/msg/VelocityLimit"](
            stamp=self.b.time(t_ns), max_velocity=float(plan["target_speed_mps"]),
            use_constraints=False, constraints=c, sender="evoeye")

    def mrm(self, t_ns: int, plan: dict) -> Any:
        braking = plan["decision"] == "emergency_brake"
        return self.b.t["autoware_adapi_v1_msgs/msg/MrmState"](
            stamp=self.b.time(t_ns), state=2 if braking else 1, behavior=2 if braking else 1)


def run_messages(log: Path) -> tuple[dict[str, Any], list[dict[str, dict[str, Any]]]]:
    """A native run log's metadata and, per frame, its messages by topic."""
    topics = [TOPICS.localization, TOPICS.obstacles, TOPICS.predictions, TOPICS.plan,
              TOPICS.control, TOPICS.ground_truth]
    run = read_run(log, topics=topics)
    per_topic = [[m for _, m in run.messages(t)] for t in topics]
    return run.metadata, [dict(zip(topics, ms, strict=True)) for ms in zip(*per_topic,
                                                                            strict=True)]


def _times(first_ns: int, last_ns: int, period_ns: int) -> range:
    return range(first_ns, last_ns + 1, period_ns)


def schedule(frames: list[dict[str, dict[str, Any]]], rates: Rates
             ) -> Iterator[tuple[str, int, Any]]:
    """When a stack at `rates` publishes what, over a run's frames: (kind, t ns, what), kind
    `odometry` (the localization, linear in time between two frames), `control` (the frame
    in force), `objects`, `planning` and `truth` (the frame); odometry first, then control,
    then frame by frame (a stable sort by time keeps this order among equal times)."""
    times = [round(f[TOPICS.localization]["t_s"] * 1e9) for f in frames]

    def frame_at(t_ns: int) -> int:  # the latest frame not after t_ns
        return int(np.searchsorted(times, t_ns, side="right")) - 1

    for t_ns in _times(times[0], times[-1], rates.odometry_ns):
        k = frame_at(t_ns)
        loc = frames[k][TOPICS.localization]
        if times[k] < t_ns and k + 1 < len(frames):
            w = (t_ns - times[k]) / (times[k + 1] - times[k])
            loc = _interp_loc(loc, frames[k + 1][TOPICS.localization], w)
        yield "odometry", t_ns, loc
    for t_ns in _times(times[0], times[-1], rates.control_ns):
        yield "control", t_ns, frames[frame_at(t_ns)]
    for t_ns, f in zip(times, frames, strict=True):
        offset = t_ns - times[0]
        if offset % rates.objects_ns == 0:
            yield "objects", t_ns, f
        if offset % rates.planning_ns == 0:
            yield "planning", t_ns, f
        yield "truth", t_ns, f


def bag_messages(log: Path, mapping: Mapping, rates: Rates, collision: bool = False
                 ) -> tuple[dict[str, Any], list[tuple[int, str, str, Any]]]:
    """The run's metadata and its bag messages [(log ns, topic, type, message)], time-sorted."""
    meta, frames = run_messages(log)
    ex, T = Exporter(mapping), mapping.topics
    out: list[tuple[int, int, str, str, Any]] = []

    def add(t_ns: int, order: int, topic: str, msgtype: str, msg: Any) -> None:
        if topic:
            out.append((t_ns, order, topic, msgtype, msg))

    for kind, t_ns, f in schedule(frames, rates):
        if kind == "odometry":
            add(t_ns, 1, T.odometry, "nav_msgs/msg/Odometry",
                ex.odometry(t_ns, f["x_m"], f["y_m"], f["heading_rad"], f["speed_mps"]))
            add(t_ns, 2, T.acceleration, "geometry_msgs/msg/AccelWithCovarianceStamped",
                ex.acceleration(t_ns, f["accel_mps2"]))
        elif kind == "control":
            add(t_ns, 3, T.control, "autoware_control_msgs/msg/Control",
                ex.control(t_ns, f[TOPICS.control], f[TOPICS.localization]["speed_mps"]))
        elif kind == "objects":
            obs = f[TOPICS.obstacles]
            add(t_ns, 0, T.objects, "autoware_perception_msgs/msg/TrackedObjects",
                ex.obstacles(t_ns, obs))
            add(t_ns, 0, T.predicted, "autoware_perception_msgs/msg/PredictedObjects",
                ex.predicted(t_ns, f[TOPICS.predictions], obs))
        elif kind == "planning":
            plan = f[TOPICS.plan]
            add(t_ns, 0, T.trajectory, "autoware_planning_msgs/msg/Trajectory",
                ex.trajectory(t_ns, plan))
            for topic, meant in mapping.planning_factors.items():
                add(t_ns, 0, topic, "autoware_internal_planning_msgs/msg/PlanningFactorArray",
                    ex.factors(t_ns, topic, meant, plan))
            add(t_ns, 0, T.velocity_limit, "autoware_internal_planning_msgs/msg/VelocityLimit",
                ex.velocity_limit(t_ns, plan))
            add(t_ns, 0, T.mrm_state, "autoware_adapi_v1_msgs/msg/MrmState", ex.mrm(t_ns, plan))
        else:
            gt = f[TOPICS.ground_truth]
            add(t_ns, 0, T.ground_truth_objects, "autoware_perception_msgs/msg/TrackedObjects",
                ex.truth_objects(t_ns, gt))
            add(t_ns, 0, T.ground_truth_ego, "nav_msgs/msg/Odometry",
                ex.odometry(t_ns, gt["x_m"][0], gt["y_m"][0], gt["heading_rad"][0],
                            gt["speed_mps"][0]))
            if collision:
                add(t_ns, 0, T.collision, "std_msgs/msg/Bool",
                    ex.b.t["std_msgs/msg/Bool"](data=bool(gt["ego_collision"])))
    out.sort(key=lambda m: (m[0], m[1]))
    return meta, [(t, topic, msgtype, msg) for t, _, topic, msgtype, msg in out]


def write_bag(dest: str | Path, messages: list[tuple[int, str, str, Any]],
              custom: dict[str, str] | None = None, *, store: Any = None) -> Path:
    """Write [(log ns, topic, type, message)] as the rosbag2 MCAP folder `dest` (replaced if
    it exists; written beside it first, so a killed export leaves no half bag under its name)."""
    import shutil

    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    dest = Path(dest)
    partial = dest.with_name(f".{dest.name}.partial")  # the bag folder is named in its files
    shutil.rmtree(partial, ignore_errors=True)
    tmp = partial / dest.name
    store = store or typestore()
    writer = Writer(tmp, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)  # zstd chunks
    for key, value in (custom or {}).items():
        writer.set_custom_data(key, value)
    with writer:
        conns: dict[str, Any] = {}
        for t_ns, topic, msgtype, msg in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(conns[topic], t_ns, store.serialize_cdr(msg, msgtype))
    shutil.rmtree(dest, ignore_errors=True)
    tmp.rename(dest)
    partial.rmdir()
    return dest


def export_run(log: str | Path, out_dir: str | Path, *, mapping: Mapping | None = None,
               rates: str = "realistic", collision: bool = False) -> Path:
    """Write the run log as the rosbag2 folder `<out_dir>/<scenario id>/` (MCAP); its path.
    An existing folder of that name is replaced."""
    meta, messages = bag_messages(Path(log), mapping or Mapping(), RATES[rates], collision)
    identity = orjson.dumps({k: meta[k] for k in (*IDENTITY, *OPTIONAL_IDENTITY)}).decode()
    return write_bag(Path(out_dir) / str(meta["scenario_id"]), messages, {RUN_KEY: identity})
