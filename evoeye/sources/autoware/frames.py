"""Autoware messages in receive order → evoeye frames on a 20 Hz clock, one frame at a time.

Autoware publishes each topic at its own rate (odometry ≈ 50 Hz, trajectory ≈ 10 Hz, control
≈ 33 Hz). The frame clock ticks every 1/rate_hz from the first odometry stamp; a frame holds,
per topic, the latest message whose header stamp is not after the frame time, and records that
message's age. A frame is closed when an odometry message stamped after it arrives (or at the
end of the recording): only what had arrived by then is in it — what a monitor beside the
running stack would have known. `evoeye import` and `evoeye watch` both feed this assembler
messages in receive order, so both give the same frames, and the same alarms.

Frames start once every required topic has a message; from then on a required topic silent for
more than `max_gap_s`, or a stamp older than its predecessor's, is an error naming the topic.
Positions are re-origined once per run (the first ego position, truncated to whole `ORIGIN_M`):
the warehouse keeps per-point positions as float32, 0.25 m apart at UTM northings but within
0.1 mm up to 1 km; a position under 1 km from the map's origin is kept as it is. Frame times
count from the whole second before the first frame (`t_origin_ns`).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from evoeye.log import TOPICS
from evoeye.log.channels import AGES_TOPIC
from evoeye.sources.autoware import grids
from evoeye.sources.autoware.config import REQUIRED_ROLES, Mapping
from evoeye.sources.autoware.convert import (
    Context,
    ConversionError,
    Ego,
    TrackIds,
    converter,
    stamp_ns,
)
from evoeye.sources.autoware.labels import GroundTruth

ORIGIN_M = 1000.0
HELD = 64  # recent messages kept per topic (a frame takes the latest not after its time)


class SourceError(ValueError):
    """A recording that cannot become an evoeye run: names the topic and the problem."""

    def __init__(self, topic: str, problem: str):
        super().__init__(f"{topic}: {problem}")
        self.topic = topic
        self.problem = problem


@dataclass
class Frame:
    """One assembled frame: the evoeye channel messages by topic."""

    index: int
    t_ns: int  # the frame time, on the recording's clock
    messages: dict[str, dict[str, Any]]


@dataclass
class FrameAssembler:
    """Feed `push` the messages of a recording in receive order; it yields the closed frames."""

    mapping: Mapping
    label_source: str
    lookup: Callable[[str, str], Any] = converter  # (role, type name) → converter (another
    # stack's: `evoeye.sources.apollo.convert.converter`)
    stamp: Callable[[Any], int | None] = stamp_ns  # a message's own time, ns
    roles: dict[str, str] = field(init=False)  # topic → role
    held: dict[str, deque] = field(init=False)  # role → deque of (stamp ns, value)
    frames: int = 0  # emitted so far
    empty_object_frames: int = 0  # frames whose tracked-object list was empty
    recovered_plan_times: int = 0  # trajectories whose all-zero times were rebuilt
    origin: tuple[float, float] | None = None
    t_origin_ns: int | None = None
    _next_ns: int | None = None  # the next frame's time
    _accel: tuple[int, float, float] | None = None  # (stamp, speed, accel) from odometry alone

    def __post_init__(self) -> None:
        # each factor topic is held apart: `factor:<topic>`
        self.roles = {t: (f"factor:{t}" if r == "factor" else r)
                      for t, r in self.mapping.roles().items()}
        self.held = {role: deque(maxlen=HELD) for role in set(self.roles.values())}
        v = self.mapping.vehicle
        self.truth = GroundTruth(self.label_source, v.length_m, v.width_m)
        self.period_ns = round(1e9 / self.mapping.rate_hz)
        self.context = Context(v, TrackIds())  # one run's track ids, shared by every topic

    def push(self, topic: str, msgtype: str, msg: Any, log_ns: int) -> Iterator[Frame]:
        """Take one message; yield the frames it closes (an odometry message stamped later)."""
        role = self.roles.get(topic)
        if role is None:
            return
        try:
            value = self.lookup(role.partition(":")[0], msgtype)(msg, self.context)
        except ConversionError as e:
            raise SourceError(topic, str(e)) from None
        stamp = self.stamp(msg)
        stamp = log_ns if stamp is None else stamp
        held = self.held[role]
        if held and stamp < held[-1][0]:
            raise SourceError(topic, f"out-of-order stamps: {stamp / 1e9:.3f} s after "
                                     f"{held[-1][0] / 1e9:.3f} s")
        if role == "odometry":
            yield from self._close_before(stamp)
            self._track_accel(stamp, value)
            if self.origin is None:
                self.origin = tuple(math.trunc(c / ORIGIN_M) * ORIGIN_M
                                    for c in (value.x_m, value.y_m))
                self._next_ns = stamp
        if role == "trajectory" and value.times_recovered:
            self.recovered_plan_times += 1
        held.append((stamp, value))

    def finish(self) -> Iterator[Frame]:
        """The frames up to the last odometry stamp (the end of the recording)."""
        odometry = self.held["odometry"]
        if odometry:
            yield from self._close_before(odometry[-1][0] + 1)

    def _track_accel(self, stamp: int, ego: Ego) -> None:
        if self._accel is not None and stamp > self._accel[0]:
            dv = ego.speed_mps - self._accel[1]
            self._accel = (stamp, ego.speed_mps, dv / ((stamp - self._accel[0]) / 1e9))
        else:
            self._accel = (stamp, ego.speed_mps, 0.0 if self._accel is None else self._accel[2])

    def _latest(self, role: str, t_ns: int) -> tuple[int, Any] | None:
        for stamp, value in reversed(self.held.get(role, ())):
            if stamp <= t_ns:
                return stamp, value
        return None

    def _close_before(self, stamp: int) -> Iterator[Frame]:
        while self._next_ns is not None and self._next_ns < stamp:
            t_ns = self._next_ns
            self._next_ns += self.period_ns
            frame = self._frame(t_ns)
            if frame is not None:
                yield frame

    def _frame(self, t_ns: int) -> Frame | None:
        got = {role: self._latest(role, t_ns) for role in self.held}
        missing = [r for r in REQUIRED_ROLES if got[r] is None]
        if missing:
            if self.frames:  # never after the start: held messages stay
                raise SourceError(getattr(self.mapping.topics, missing[0]), "no message")
            return None  # before every required topic has begun
        ages = {r: (t_ns - got[r][0]) / 1e9 for r in REQUIRED_ROLES}
        for role, age in ages.items():
            if age > self.mapping.max_gap_s:
                raise SourceError(getattr(self.mapping.topics, role),
                                  f"gap of {age:.2f} s before the frame at "
                                  f"{t_ns / 1e9:.2f} s (over {self.mapping.max_gap_s} s)")
        if self.t_origin_ns is None:
            self.t_origin_ns = t_ns - t_ns % 1_000_000_000
        t_s = (t_ns - self.t_origin_ns) / 1e9
        frame = Frame(self.frames, t_ns, self._messages(t_s, got, ages))
        self.frames += 1
        return frame

    def _messages(self, t_s: float, got: dict[str, Any], ages: dict[str, float]
                  ) -> dict[str, dict[str, Any]]:
        origin, v = self.origin, self.mapping.vehicle
        ego: Ego = got["odometry"][1]
        accel = got["acceleration"][1] if got.get("acceleration") else \
            ego.accel_mps2 if ego.accel_mps2 is not None else self._accel[2]
        objects = got["objects"][1]
        if not objects["track_id"]:
            self.empty_object_frames += 1
        steering, accel_cmd = got["control"][1]
        truth_ego = got["ground_truth_ego"][1] if got.get("ground_truth_ego") else ego
        gt_objects = got["ground_truth_objects"][1] if got.get("ground_truth_objects") else None
        colliding = got["collision"][1] if got.get("collision") else None
        return {
            TOPICS.localization: {"t_s": t_s, "x_m": ego.x_m - origin[0],
                                  "y_m": ego.y_m - origin[1], "heading_rad": ego.heading_rad,
                                  "speed_mps": ego.speed_mps, "accel_mps2": accel},
            TOPICS.obstacles: {"t_s": t_s, **objects,
                               "x_m": [x - origin[0] for x in objects["x_m"]],
                               "y_m": [y - origin[1] for y in objects["y_m"]]},
            TOPICS.predictions: {"t_s": t_s, **grids.predictions(
                got["predicted"][1], ages["predicted"], origin)},
            TOPICS.plan: {"t_s": t_s, **self._decision(got),
                          **grids.plan_points(got["trajectory"][1], ego, ages["trajectory"],
                                             origin)},
            TOPICS.control: {
                "t_s": t_s, "throttle": accel_cmd / v.accel_max_mps2 if accel_cmd > 0 else 0.0,
                "brake": accel_cmd / v.accel_min_mps2 if accel_cmd < 0 else 0.0,
                "steering_rad": steering, "accel_cmd_mps2": accel_cmd},
            TOPICS.ground_truth: self.truth.message(t_s, truth_ego, accel, gt_objects, colliding,
                                                    origin),
            AGES_TOPIC: {"t_s": t_s, "localization_s": ages["odometry"],
                          "obstacles_s": ages["objects"], "predictions_s": ages["predicted"],
                          "plan_s": ages["trajectory"], "control_s": ages["control"]},
        }

    def _decision(self, got: dict[str, Any]) -> dict[str, Any]:
        """decision, target speed and leader: those the trajectory carries, if it does (Apollo);
        else an operating MRM brakes in an emergency, or the first factor topic with a factor
        names the decision, cruise if none has one. The target speed is the velocity limit in
        force (the plan's top speed without one)."""
        traj = got["trajectory"][1]
        if traj.decision is not None:
            decision, target, leader = traj.decision
            target = float(traj.speed_mps.max()) if target is None else target
            return {"decision": decision, "target_speed_mps": target, "leader_track_id": leader}
        limit = got.get("velocity_limit")
        target = limit[1] if limit else float(traj.speed_mps.max())
        decision, leader = "cruise", -1
        if got.get("mrm_state") and got["mrm_state"][1]:
            decision = "emergency_brake"
        else:
            for topic, meant in self.mapping.planning_factors.items():
                factor = got.get(f"factor:{topic}")
                if factor is not None and factor[1] is not None:
                    decision, leader = meant, factor[1]
                    break
        return {"decision": decision, "target_speed_mps": target, "leader_track_id": leader}
