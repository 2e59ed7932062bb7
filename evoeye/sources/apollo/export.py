"""An evoeye run log → a cyber record of Apollo's messages, with Apollo's conventions.

The channels are Apollo's (`run.APOLLO_TOPICS`): a LocalizationEstimate of the rear-axle centre
(heading, world-frame velocity and acceleration), PerceptionObstacles (box and polygon, world
velocity, type and sub-type), PredictionObstacles (each mode from the obstacle's position at
relative time 0), an ADCTrajectory (rear-axle points, relative times; the decision as a
DecisionResult: `yield` a main stop and an object yield, `follow` an object follow, `proceed`
an object overtake, `emergency_brake` an e-stop; the target speed as the target lane's speed
limit) and a ControlCommand (throttle and brake in %, steering in % of the range). The ground
truth goes on the simulation channels, the run's identity on `run.RUN_CHANNEL`. Rates as for
Autoware (`evoeye.sources.autoware.export.RATES`, `schedule`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import orjson

from evoeye.log import TOPICS
from evoeye.sources.apollo.convert import CLASSES, ApolloVehicle
from evoeye.sources.apollo.protos import vendored
from evoeye.sources.apollo.record import write_record
from evoeye.sources.apollo.run import APOLLO_TOPICS, RUN_CHANNEL
from evoeye.sources.autoware.bag import IDENTITY, OPTIONAL_IDENTITY
from evoeye.sources.autoware.export import RATES, Rates, run_messages, schedule

INT32 = 2**31
OBJECT_DECISION = {"yield": "yield", "follow": "follow", "proceed": "overtake"}


class ApolloExporter:
    """Builds the Apollo messages of one run's frames."""

    def __init__(self, vehicle: ApolloVehicle) -> None:
        self.t = vendored()
        self.vehicle = vehicle
        self.ahead = vehicle.centre_ahead_m

    def _stamped(self, name: str, t_ns: int, **fields: Any) -> Any:
        msg = self.t[name](**fields)
        msg.header.timestamp_sec = t_ns / 1e9
        msg.header.module_name = "evoeye"
        return msg

    def localization(self, t_ns: int, x: float, y: float, h: float, speed: float,
                     accel: float = 0.0) -> Any:
        msg = self._stamped("apollo.localization.LocalizationEstimate", t_ns,
                            measurement_time=t_ns / 1e9)
        p, c, s = msg.pose, math.cos(h), math.sin(h)
        p.position.x, p.position.y = x - self.ahead * c, y - self.ahead * s
        p.heading = h
        p.orientation.qz, p.orientation.qw = math.sin((h - math.pi / 2) / 2), \
            math.cos((h - math.pi / 2) / 2)  # the IMU's, a quarter turn off the heading
        p.linear_velocity.x, p.linear_velocity.y = speed * c, speed * s
        p.linear_acceleration.x, p.linear_acceleration.y = accel * c, accel * s
        return msg

    def obstacles(self, t_ns: int, ids: list, classes: list, x: list, y: list, h: list,
                  vx: list, vy: list, length: list, width: list, confidence: list) -> Any:
        msg = self._stamped("apollo.perception.PerceptionObstacles", t_ns)
        for i, track in enumerate(ids):
            if not -INT32 <= track < INT32:
                raise ValueError(f"track id {track} does not fit Apollo's int32 obstacle id")
            kind, sub = next(((k, s) for name, k, s in CLASSES if name == classes[i]), (0, 0))
            o = msg.perception_obstacle.add(id=int(track), theta=h[i], length=length[i],
                                            width=width[i], height=1.5, type=kind,
                                            sub_type=sub, confidence=confidence[i],
                                            timestamp=t_ns / 1e9)
            o.position.x, o.position.y = x[i], y[i]
            o.velocity.x, o.velocity.y = vx[i], vy[i]
            c, s = math.cos(h[i]), math.sin(h[i])
            for da, dc in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
                a, b = da * length[i] / 2, dc * width[i] / 2
                o.polygon_point.add(x=x[i] + c * a - s * b, y=y[i] + s * a + c * b)
        return msg

    def perception(self, t_ns: int, o: dict) -> Any:
        return self.obstacles(t_ns, o["track_id"], o["obj_class"], o["x_m"], o["y_m"],
                              o["heading_rad"], o["vx_mps"], o["vy_mps"], o["length_m"],
                              o["width_m"], o["confidence"])

    def truth(self, t_ns: int, g: dict) -> Any:
        n = len(g["actor_id"]) - 1
        return self.obstacles(t_ns, g["actor_id"][1:], ["car"] * n, g["x_m"][1:], g["y_m"][1:],
                              g["heading_rad"][1:], g["vx_mps"][1:], g["vy_mps"][1:],
                              g["length_m"][1:], g["width_m"][1:], [1.0] * n)

    def prediction(self, t_ns: int, p: dict, o: dict) -> Any:
        msg = self._stamped("apollo.prediction.PredictionObstacles", t_ns)
        now = {tid: (x, y) for tid, x, y in zip(o["track_id"], o["x_m"], o["y_m"], strict=True)}
        by_track: dict[int, Any] = {}
        for i, tid in enumerate(p["track_id"]):
            if tid not in by_track:
                po = by_track[tid] = msg.prediction_obstacle.add(timestamp=t_ns / 1e9)
                po.perception_obstacle.id = int(tid)
                po.perception_obstacle.length = p["length_m"][i]
                po.perception_obstacle.width = p["width_m"][i]
            x0, y0 = now.get(tid, (p["x_m"][i][0], p["y_m"][i][0]))
            traj = by_track[tid].trajectory.add(probability=p["mode_prob"][i])
            for k, (x, y) in enumerate(zip([x0, *p["x_m"][i]], [y0, *p["y_m"][i]],
                                           strict=True)):
                q = traj.trajectory_point.add(relative_time=k * p["dt_s"])
                q.path_point.x, q.path_point.y = x, y
        return msg

    def planning(self, t_ns: int, p: dict) -> Any:
        msg = self._stamped("apollo.planning.ADCTrajectory", t_ns)
        for t, x, y, h, v, a in zip(p["t_rel_s"], p["x_m"], p["y_m"], p["heading_rad"],
                                    p["speed_mps"], p["accel_mps2"], strict=True):
            q = msg.trajectory_point.add(v=v, a=a, relative_time=t)
            q.path_point.x = x - self.ahead * math.cos(h)
            q.path_point.y = y - self.ahead * math.sin(h)
            q.path_point.theta = h
        main = msg.decision.main_decision
        main.target_lane.add(speed_limit=p["target_speed_mps"])
        decision = p["decision"]
        if decision == "emergency_brake":
            msg.estop.is_estop = True
            main.estop.SetInParent()
        elif decision in OBJECT_DECISION:
            d = msg.decision.object_decision.decision.add(perception_id=p["leader_track_id"])
            getattr(d.object_decision.add(), OBJECT_DECISION[decision]).SetInParent()
        return msg

    def control(self, t_ns: int, c: dict) -> Any:
        return self._stamped("apollo.control.ControlCommand", t_ns,
                             throttle=100.0 * c["throttle"], brake=100.0 * c["brake"],
                             steering_target=100.0 * c["steering_rad"] /
                             self.vehicle.max_steer_rad, acceleration=c["accel_cmd_mps2"])


def record_messages(log: Path, rates: Rates, vehicle: ApolloVehicle | None = None
                    ) -> tuple[dict[str, Any], list[tuple[str, int, Any]]]:
    """The run's metadata and its record messages [(channel, t ns, message)], time-sorted."""
    meta, frames = run_messages(log)
    ex, T = ApolloExporter(vehicle or ApolloVehicle()), APOLLO_TOPICS
    out: list[tuple[int, int, str, Any]] = []
    for kind, t_ns, f in schedule(frames, rates):
        if kind == "odometry":
            out.append((t_ns, 1, T.odometry, ex.localization(
                t_ns, f["x_m"], f["y_m"], f["heading_rad"], f["speed_mps"], f["accel_mps2"])))
        elif kind == "control":
            out.append((t_ns, 2, T.control, ex.control(t_ns, f[TOPICS.control])))
        elif kind == "objects":
            obs = f[TOPICS.obstacles]
            out.append((t_ns, 0, T.objects, ex.perception(t_ns, obs)))
            out.append((t_ns, 0, T.predicted, ex.prediction(t_ns, f[TOPICS.predictions], obs)))
        elif kind == "planning":
            out.append((t_ns, 0, T.trajectory, ex.planning(t_ns, f[TOPICS.plan])))
        else:
            gt = f[TOPICS.ground_truth]
            out.append((t_ns, 0, T.ground_truth_objects, ex.truth(t_ns, gt)))
            out.append((t_ns, 0, T.ground_truth_ego, ex.localization(
                t_ns, gt["x_m"][0], gt["y_m"][0], gt["heading_rad"][0], gt["speed_mps"][0])))
    identity = orjson.dumps({k: meta[k] for k in (*IDENTITY, *OPTIONAL_IDENTITY)}).decode()
    first = min(t for t, *_ in out)
    out.append((first, -1, RUN_CHANNEL, vendored()["apollo.common.Header"](
        module_name=identity)))
    out.sort(key=lambda m: (m[0], m[1]))
    return meta, [(channel, t, msg) for t, _, channel, msg in out]


def export_record(log: str | Path, out_dir: str | Path, *, rates: str = "realistic",
                  vehicle: ApolloVehicle | None = None) -> Path:
    """Write the run log as the cyber record `<out_dir>/<scenario id>.record`; its path."""
    meta, messages = record_messages(Path(log), RATES[rates], vehicle)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return write_record(out_dir / f"{meta['scenario_id']}.record", messages)
