"""Prediction: lane-following for cars on a lane, constant velocity otherwise."""

import math

import numpy as np
from conftest import crossing_road, curved_road, ego_at, obstacles, straight_road

from evoeye.ads import ADSConfig
from evoeye.ads.prediction import LaneOrCVPredictor

EGO = ego_at(0.0, 0.0)


def predict(road, rows):
    return LaneOrCVPredictor(road, ADSConfig.cautious().prediction).predict(obstacles(rows), EGO)


def test_a_lane_aligned_car_follows_the_lane_centre():
    p = predict(straight_road(), [(30.0, 4.4, 0.02, 20.0)])  # 0.4 m off, slightly turned
    assert p.model == ["lane"]
    assert p.x_m.shape == (1, 30) and math.isclose(p.dt_s, 0.1)
    assert np.allclose(p.y_m, 4.0)  # on the centre line, not drifting with the heading
    along = 20.0 * math.cos(0.02)
    assert np.allclose(p.x_m[0], 30.0 + along * (np.arange(30) + 1) * 0.1, atol=1e-6)


def test_a_car_on_a_curved_lane_follows_the_curve():
    radius = 60.0
    a0 = -0.5  # position on the arc (angle from its centre), heading along it
    x, y = radius * math.cos(a0), radius + radius * math.sin(a0)
    p = predict(curved_road(radius), [(x, y, a0 + math.pi / 2, 15.0)])
    assert p.model == ["lane"]
    dist = np.hypot(p.x_m[0], p.y_m[0] - radius)
    assert np.allclose(dist, radius, atol=0.05)
    angle = np.arctan2(p.y_m[0, -1] - radius, p.x_m[0, -1])
    assert math.isclose(angle - a0, 15.0 * 3.0 / radius, abs_tol=0.02)  # 45 m along the arc


def test_a_car_with_strong_lateral_motion_is_predicted_at_constant_velocity():
    heading = -math.atan2(1.5, 20.0)  # drifting right at 1.5 m/s: a cut-in into y = 0
    p = predict(straight_road(), [(30.0, 4.0, heading, math.hypot(20.0, 1.5))])
    assert p.model == ["cv"]
    t = (np.arange(30) + 1) * 0.1
    assert np.allclose(p.x_m[0], 30.0 + 20.0 * t) and np.allclose(p.y_m[0], 4.0 - 1.5 * t)


def test_cut_in_recognition_needs_lateral_speed_above_the_threshold():
    slow = -math.atan2(0.4, 20.0)  # 0.4 m/s lateral: below the 0.6 m/s threshold
    p = predict(straight_road(), [(30.0, 3.8, slow, 20.0)])
    assert p.model == ["lane"] and np.allclose(p.y_m, 4.0)


def test_a_car_off_every_lane_gets_constant_velocity():
    p = predict(straight_road(), [(30.0, 20.0, 0.0, 10.0)])
    assert p.model == ["cv"]


def test_the_lane_is_chosen_by_heading_where_lanes_cross():
    p = predict(crossing_road(), [(0.4, 0.3, 0.0, 10.0), (0.3, 0.4, math.pi / 2, 10.0)])
    assert p.model == ["lane", "lane"]
    assert np.allclose(p.y_m[0], 0.0) and p.x_m[0, -1] > 29.0  # eastwards along y = 0
    assert np.allclose(p.x_m[1], 0.0) and p.y_m[1, -1] > 29.0  # northwards along x = 0


def test_no_obstacles_gives_empty_predictions():
    p = predict(straight_road(), [])
    assert p.x_m.shape == (0, 30) and p.model == [] and len(p.track_id) == 0


def test_a_map_without_lanes_predicts_constant_velocity():
    road = straight_road()
    bare = type(road)(name="bare", lanes=(), route=road.route)
    p = predict(bare, [(30.0, 0.0, 0.0, 10.0)])
    assert p.model == ["cv"] and np.allclose(p.x_m[0, -1], 60.0)
