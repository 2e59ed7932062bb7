"""Write tests/data/apollo/foreign.record.xz with cyber-record and apollo-modules' protos, not
with evoeye: half a second of a drive at Apollo's rates (localization, chassis and control
100 Hz; perception, prediction and planning 10 Hz), one obstacle ahead.

Run it in the scratch venv of make_descriptors.py (cyber-record and apollo-modules pin a
protobuf evoeye cannot install beside its own):

    /tmp/apollo/bin/python tests/data/apollo/make_foreign_record.py

`expected()` gives the values written, for the tests to check what evoeye reads.
"""

from __future__ import annotations

import math
from pathlib import Path

OUT = Path(__file__).resolve().parent / "foreign.record"  # then: xz -9 foreign.record
T0_NS = 1_700_000_000_050_000_000
X0, Y0, HEADING = 587_123.4, 4_141_234.5, 0.3  # UTM, the lane heading
SPEED = 10.0
CHANNELS = {  # channel → period ns
    "/apollo/localization/pose": 10_000_000,
    "/apollo/canbus/chassis": 10_000_000,
    "/apollo/control": 10_000_000,
    "/apollo/perception/obstacles": 100_000_000,
    "/apollo/prediction": 100_000_000,
    "/apollo/planning": 100_000_000,
}
DURATION_NS = 500_000_000
OBSTACLE_ID = 4242


def expected(t_s: float) -> dict[str, float]:
    """The ego's pose and speed, and the obstacle's position, at t_s after T0."""
    s = SPEED * t_s
    c, h = math.cos(HEADING), math.sin(HEADING)
    return {"x": X0 + c * s, "y": Y0 + h * s, "heading": HEADING, "speed": SPEED,
            "obs_x": X0 + c * 40.0, "obs_y": Y0 + h * 40.0}


def main() -> None:
    from apollo_modules.modules.common_msgs.chassis_msgs import chassis_pb2
    from apollo_modules.modules.common_msgs.control_msgs import control_cmd_pb2
    from apollo_modules.modules.common_msgs.localization_msgs import localization_pb2
    from apollo_modules.modules.common_msgs.perception_msgs import perception_obstacle_pb2
    from apollo_modules.modules.common_msgs.planning_msgs import planning_pb2
    from apollo_modules.modules.common_msgs.prediction_msgs import prediction_obstacle_pb2
    from cyber_record.record import Record

    def header(msg, t_ns: int, seq: int) -> None:
        msg.header.timestamp_sec = t_ns / 1e9
        msg.header.sequence_num = seq
        msg.header.module_name = "foreign"

    def build(channel: str, t_ns: int, seq: int):
        e = expected((t_ns - T0_NS) / 1e9)
        if channel.endswith("pose"):
            m = localization_pb2.LocalizationEstimate()
            m.pose.position.x, m.pose.position.y = e["x"], e["y"]
            m.pose.orientation.qw = math.cos((e["heading"] - math.pi / 2) / 2)
            m.pose.orientation.qz = math.sin((e["heading"] - math.pi / 2) / 2)
            m.pose.heading = e["heading"]
            m.pose.linear_velocity.x = SPEED * math.cos(HEADING)
            m.pose.linear_velocity.y = SPEED * math.sin(HEADING)
            m.measurement_time = t_ns / 1e9
        elif channel.endswith("chassis"):
            m = chassis_pb2.Chassis(speed_mps=SPEED, throttle_percentage=12.0,
                                    brake_percentage=0.0, steering_percentage=0.0)
        elif channel.endswith("control"):
            m = control_cmd_pb2.ControlCommand(throttle=12.0, brake=0.0, steering_target=0.0,
                                               acceleration=0.2)
        elif channel.endswith("obstacles"):
            m = perception_obstacle_pb2.PerceptionObstacles()
            o = m.perception_obstacle.add(id=OBSTACLE_ID, theta=HEADING, length=4.5,
                                          width=1.8, height=1.5, type=5)  # VEHICLE
            o.position.x, o.position.y = e["obs_x"], e["obs_y"]
            for dx, dy in ((-2.25, -0.9), (2.25, -0.9), (2.25, 0.9), (-2.25, 0.9)):
                p = o.polygon_point.add()
                p.x = e["obs_x"] + dx * math.cos(HEADING) - dy * math.sin(HEADING)
                p.y = e["obs_y"] + dx * math.sin(HEADING) + dy * math.cos(HEADING)
        elif channel.endswith("prediction"):
            m = prediction_obstacle_pb2.PredictionObstacles()
            po = m.prediction_obstacle.add(predicted_period=8.0)
            po.perception_obstacle.id = OBSTACLE_ID
            traj = po.trajectory.add(probability=1.0)
            for k in range(5):
                p = traj.trajectory_point.add(relative_time=0.5 * k)
                p.path_point.x, p.path_point.y = e["obs_x"], e["obs_y"]
        else:
            m = planning_pb2.ADCTrajectory(total_path_length=20.0, total_path_time=2.0)
            for k in range(21):
                p = m.trajectory_point.add(relative_time=0.1 * k, v=SPEED, a=0.0)
                p.path_point.x = e["x"] + SPEED * 0.1 * k * math.cos(HEADING)
                p.path_point.y = e["y"] + SPEED * 0.1 * k * math.sin(HEADING)
                p.path_point.theta = HEADING
        header(m, t_ns, seq)
        return m

    rows = []
    for channel, period in CHANNELS.items():
        for seq, t in enumerate(range(T0_NS, T0_NS + DURATION_NS, period)):
            rows.append((t, channel, seq))
    rows.sort()
    with Record(str(OUT), mode="w") as record:
        for t, channel, seq in rows:
            record.write(channel, build(channel, t, seq), t)
    print(OUT, OUT.stat().st_size, "bytes")


if __name__ == "__main__":
    main()
