"""Oracle modules: ground-truth perception, true futures, the careful planner, ideal control."""

import math

import numpy as np
from conftest import DT_S, ego_at, make_scene, obstacles, straight_road
from test_control import plan_of

from evoeye.ads import ADS, ADSConfig
from evoeye.ads.config import ControlConfig, PlanningConfig, PredictionConfig
from evoeye.ads.oracle import (
    GroundTruthPerception,
    IdealController,
    TrueFuturePredictor,
    TrueFutures,
    careful_planner,
    careful_planning,
)


def test_ground_truth_perception_reports_every_actor_exactly_and_now():
    scene = make_scene(3.25, [(0, 0, 0, 20), (200, 40, 1.0, 7), (-1, 3.5, 3.0, 0.5), (9, 0, 0, 3)])
    scene.actor_id = np.array([0, 7, 3, 12])
    obs = GroundTruthPerception().perceive(scene, ego_at(0, 0, t_s=3.25))
    assert obs.t_s == 3.25  # published at the scene's time: no latency
    np.testing.assert_array_equal(obs.track_id, [7, 3, 12])  # far and behind actors included
    np.testing.assert_array_equal(obs.x_m, scene.x_m[1:])
    np.testing.assert_array_equal(obs.y_m, scene.y_m[1:])
    np.testing.assert_allclose(obs.vx_mps, scene.vx_mps[1:])
    np.testing.assert_allclose(obs.vy_mps, scene.vy_mps[1:])
    assert (obs.confidence == 1.0).all()


def circling_scenes(n_frames: int) -> list:
    """Actor 1 drives a circle (its future is not constant velocity), actor 2 stands still."""
    scenes = []
    for k in range(n_frames):
        t = k * DT_S
        a = 0.2 * t
        scenes.append(make_scene(t, [(0, 0, 0, 0), (50 * math.cos(a), 50 * math.sin(a),
                                                    a + math.pi / 2, 10.0), (5, -30, 0, 0)]))
    return scenes


def test_true_futures_give_each_obstacle_its_nearest_actor_s_true_future():
    scenes = circling_scenes(200)
    futures = TrueFutures.from_scenes(scenes, DT_S)
    config = PredictionConfig()
    t_s = 2.0
    # a perceived obstacle 1.5 m off (a noisy track) of actor 1, another near actor 2
    now = scenes[round(t_s / DT_S)]
    obs = obstacles([(now.x_m[1] + 1.5, now.y_m[1], 0.0, 3.0), (5.5, -30, 0, 0)], t_s=t_s)
    pred = TrueFuturePredictor(futures, config).predict(obs, ego_at(0, 0, t_s=t_s))
    k = round(config.horizon_s / config.dt_s)
    assert pred.x_m.shape == (2, k)
    frames = [round((t_s + (j + 1) * config.dt_s) / DT_S) for j in range(k)]
    np.testing.assert_allclose(pred.x_m[0], [scenes[f].x_m[1] for f in frames])
    np.testing.assert_allclose(pred.y_m[0], [scenes[f].y_m[1] for f in frames])
    np.testing.assert_allclose(pred.x_m[1], 5.0)
    np.testing.assert_array_equal(pred.track_id, obs.track_id)


def test_true_futures_continue_at_the_last_velocity_past_the_run_s_end():
    scenes = circling_scenes(41)  # ends at t = 2 s
    futures = TrueFutures.from_scenes(scenes, DT_S)
    x, y = futures.positions(np.array([2.0, 3.0]))
    last = scenes[-1]
    np.testing.assert_allclose(x[:, 0], last.x_m[1] + np.array([0.0, 1.0]) * last.vx_mps[1])
    np.testing.assert_allclose(y[:, 0], last.y_m[1] + np.array([0.0, 1.0]) * last.vy_mps[1])


def test_the_careful_planner_is_the_same_planner_configured_carefully():
    base = PlanningConfig()
    careful = careful_planning(base)
    cautious = ADSConfig.cautious().planning
    assert careful.time_headway_s > max(base.time_headway_s, cautious.time_headway_s)
    assert careful.gap_margin_s > 0.0
    assert careful.emergency_ttc_s > max(base.emergency_ttc_s, cautious.emergency_ttc_s)
    assert careful.emergency_decel_mps2 >= cautious.emergency_decel_mps2
    assert careful.yield_decel_max_mps2 >= 5.0
    planner = careful_planner(straight_road(), base, 20.0, DT_S)
    assert type(planner) is type(ADS(straight_road(), np.random.default_rng(0)).planner)
    assert planner.c == careful


def test_ideal_control_reaches_the_planned_speed_in_one_frame_within_the_limits():
    config = ControlConfig()
    ctl = IdealController(config, DT_S)
    plan = plan_of(20.0, 0.0)
    plan.speed_mps = 20.0 + 2.0 * plan.t_rel_s  # planned: +2 m/s²
    cmd = ctl.control(plan, ego_at(0.0, 10.0, 0.0, 19.95))
    v_next = 20.0 + 2.0 * DT_S
    assert math.isclose(cmd.accel_cmd_mps2, (v_next - 19.95) / DT_S)
    assert ctl.control(plan, ego_at(0.0, 10.0, 0.0, 30.0)).accel_cmd_mps2 == config.accel_min_mps2
    assert ctl.control(plan, ego_at(0.0, 10.0, 0.0, 0.0)).accel_cmd_mps2 == config.accel_max_mps2


def test_ideal_control_steers_without_a_rate_limit():
    config = ControlConfig()
    plan = plan_of(10.0, 0.0, heading=math.pi / 2)  # the path turns away to the left
    steer = IdealController(config, DT_S).control(plan, ego_at(0.0, 0.0, 0.0, 10.0)).steering_rad
    assert steer > config.max_steering_rate_radps * DT_S * 2  # far beyond one rate-limited step
    assert steer <= config.max_steering_rad


def test_an_obstacle_without_a_true_actor_keeps_its_constant_velocity():
    futures = TrueFutures.from_scenes([make_scene(k * DT_S, [(0, 0, 0, 0)]) for k in range(10)],
                                      DT_S)  # the ego alone: a detection is a false positive
    obs = obstacles([(30.0, 2.0, 0.0, 5.0)], t_s=0.2)
    pred = TrueFuturePredictor(futures, PredictionConfig()).predict(obs, ego_at(0, 0, t_s=0.2))
    np.testing.assert_allclose(pred.x_m[0], 30.0 + 5.0 * 0.1 * np.arange(1, 31))
    np.testing.assert_allclose(pred.y_m[0], 2.0)
