"""Control: pure pursuit + PID, in closed loop with the kinematic bicycle, and its limits."""

import math
from dataclasses import replace

import numpy as np
from conftest import DT_S, BicycleWorld, curved_road, ego_at, straight_road

from evoeye.ads import ADS, ADSConfig
from evoeye.ads.config import ControlConfig
from evoeye.ads.control import PurePursuitController
from evoeye.ads.messages import PlannedTrajectory


def closed_loop(road, ego, cruise, seconds):
    world = BicycleWorld(ego=list(ego))
    ads = ADS(road, np.random.default_rng(0), ADSConfig.cautious().with_cruise_speed(cruise))
    trace = []
    for _ in range(round(seconds / DT_S)):
        m = ads.step(world.scene())
        world.step(m.control.accel_cmd_mps2, m.control.steering_rad)
        trace.append((world.t_s, *world.ego))
    return np.array(trace)  # (T, 5) t, x, y, heading, speed


def test_tracks_a_straight_route_from_a_lateral_offset_and_reaches_the_set_speed():
    trace = closed_loop(straight_road(), (0.0, 1.0, 0.0, 15.0), cruise=20.0, seconds=12.0)
    t, y, v = trace[:, 0], trace[:, 2], trace[:, 4]
    assert (np.abs(y[t >= 5.0]) < 0.2).all()
    assert np.abs(y).max() <= 1.05  # no overshoot worth the name
    assert abs(v[-1] - 20.0) < 0.3


def test_tracks_a_curved_route():
    radius = 60.0
    trace = closed_loop(curved_road(radius), (0.0, 0.0, 0.0, 10.0), cruise=10.0, seconds=12.0)
    dist = np.hypot(trace[:, 1], trace[:, 2] - radius)
    assert (np.abs(dist[trace[:, 0] >= 3.0] - radius) < 0.3).all()


def plan_of(speed, accel, heading=0.0, n=41):
    t = np.arange(n) * 0.1
    return PlannedTrajectory(
        t_s=0.0, decision="cruise", target_speed_mps=speed, leader_track_id=-1, t_rel_s=t,
        x_m=math.cos(heading) * speed * t + 0.0, y_m=math.sin(heading) * speed * t + 10.0,
        heading_rad=np.full(n, heading), speed_mps=np.full(n, speed), accel_mps2=np.full(n, accel),
    )


IDEAL_ACTUATORS = replace(ControlConfig(), accel_lag_s=0.0, steering_lag_s=0.0,
                          brake_dead_time_s=0.0)


def test_acceleration_saturates_and_maps_to_brake_and_throttle():
    ctl = PurePursuitController(IDEAL_ACTUATORS, DT_S)
    hard = ctl.control(plan_of(20.0, -20.0), ego_at(0.0, 10.0, 0.0, 20.0))
    assert hard.accel_cmd_mps2 == -8.0 and hard.brake == 1.0 and hard.throttle == 0.0
    ctl = PurePursuitController(IDEAL_ACTUATORS, DT_S)
    gas = ctl.control(plan_of(20.0, 1.5), ego_at(0.0, 10.0, 0.0, 20.0))
    assert gas.accel_cmd_mps2 == 1.5 and math.isclose(gas.throttle, 0.5) and gas.brake == 0.0


def test_steering_respects_the_angle_and_rate_limits():
    config = IDEAL_ACTUATORS
    ctl = PurePursuitController(config, DT_S)
    plan = plan_of(10.0, 0.0, heading=math.pi / 2)  # the path turns away to the left
    steer = [ctl.control(plan, ego_at(0.0, 0.0, 0.0, 10.0)).steering_rad for _ in range(20)]
    steps = np.diff([0.0, *steer])
    assert (np.abs(steps) <= config.max_steering_rate_radps * DT_S + 1e-12).all()
    assert max(steer) == config.max_steering_rad


def test_holds_still_without_reversing():
    ctl = PurePursuitController(IDEAL_ACTUATORS, DT_S)
    cmd = ctl.control(plan_of(0.0, 0.0), ego_at(0.0, 10.0, 0.0, 0.02))
    assert math.isclose(cmd.accel_cmd_mps2, -0.02 / DT_S)  # exactly to zero in one frame
    cmd = ctl.control(plan_of(0.0, 0.0), ego_at(0.0, 10.0, 0.0, 0.0))
    assert cmd.accel_cmd_mps2 == 0.0


def test_brake_dead_time_then_first_order_lag():
    config = replace(ControlConfig(), accel_lag_s=0.25, brake_dead_time_s=0.1)
    ctl = PurePursuitController(config, DT_S)
    ego = ego_at(0.0, 10.0, 0.0, 20.0)
    a = [ctl.control(plan_of(20.0, -20.0), ego).accel_cmd_mps2 for _ in range(30)]
    dead = round(0.1 / DT_S)
    assert a[:dead] == [0.0] * dead  # nothing happens during the dead time
    t = (np.arange(30 - dead) + 1) * DT_S  # then −8 · (1 − e^(−t/τ))
    assert np.allclose(a[dead:], -8.0 * (1.0 - np.exp(-t / 0.25)))
    assert a[dead + 4] > -0.7 * 8.0  # one τ after the dead time: about 63 % of the request


def test_releasing_the_brake_has_no_dead_time():
    ctl = PurePursuitController(replace(ControlConfig(), brake_dead_time_s=0.2), DT_S)
    ego = ego_at(0.0, 10.0, 0.0, 20.0)
    for _ in range(20):
        braking = ctl.control(plan_of(20.0, -20.0), ego).accel_cmd_mps2
    released = ctl.control(plan_of(20.0, 1.5), ego).accel_cmd_mps2
    assert braking < -7.0 and released > braking + 1.0


def test_steering_is_lagged_behind_the_request():
    lagged = PurePursuitController(replace(IDEAL_ACTUATORS, steering_lag_s=0.3), DT_S)
    ideal = PurePursuitController(IDEAL_ACTUATORS, DT_S)
    plan = plan_of(10.0, 0.0, heading=math.pi / 2)
    ego = ego_at(0.0, 0.0, 0.0, 10.0)
    slow = [lagged.control(plan, ego).steering_rad for _ in range(40)]
    fast = [ideal.control(plan, ego).steering_rad for _ in range(40)]
    assert all(0.0 < s < f for s, f in zip(slow[:10], fast[:10], strict=True))
    assert math.isclose(slow[-1], fast[-1], rel_tol=0.05)  # it gets there


def test_the_brakes_stop_the_car_but_never_reverse_it():
    ctl = PurePursuitController(ControlConfig(), DT_S)
    for _ in range(20):
        ctl.control(plan_of(20.0, -20.0), ego_at(0.0, 10.0, 0.0, 20.0))
    cmd = ctl.control(plan_of(20.0, -20.0), ego_at(0.0, 10.0, 0.0, 0.1))
    assert math.isclose(cmd.accel_cmd_mps2, -0.1 / DT_S)
