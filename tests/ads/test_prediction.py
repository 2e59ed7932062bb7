"""Prediction: lane keeping, lane changes and lane continuations with probabilities; CV off-lane."""

import math

import numpy as np
import pytest
from conftest import crossing_road, curved_road, ego_at, lane, obstacles, polyline, straight_road

from evoeye.ads import ADSConfig
from evoeye.ads.prediction import IntentPredictor
from evoeye.scene import RoadMap

EGO = ego_at(0.0, 0.0)


def predict(road, rows, config=None):
    return IntentPredictor(road, config or ADSConfig().prediction).predict(obstacles(rows), EGO)


def branching_road() -> RoadMap:
    """An approach going north to (0, 0), then straight on, or a left turn (radius 15 m) into a
    road going west along y = 15."""
    approach = lane("approach", polyline(0.0, -100.0, math.pi / 2, 100.0))
    straight = lane("straight", polyline(0.0, 0.0, math.pi / 2, 60.0))
    a = np.linspace(0.0, math.pi / 2, 25)
    turn = lane("turn", np.stack((-15.0 + 15.0 * np.cos(a), 15.0 * np.sin(a)), axis=1))
    west = lane("west", polyline(-15.0, 15.0, math.pi, 80.0))
    return RoadMap(name="branch", lanes=(approach, straight, turn, west), route=approach)


def modes(p, track=1):
    rows = p.track_id == track
    return dict(zip([m for m, r in zip(p.model, rows, strict=True) if r], p.mode_prob[rows],
                    strict=True))


def test_a_lane_aligned_car_keeps_its_lane_along_the_centre():
    p = predict(straight_road(), [(30.0, 4.4, 0.02, 20.0)])  # 0.4 m off, slightly turned
    assert p.model[0] == "lane" and p.mode_prob[0] > 0.9
    assert p.x_m.shape == (len(p.model), 30) and math.isclose(p.dt_s, 0.1)
    assert np.allclose(p.y_m[0], 4.0)  # on the centre line, not drifting with the heading
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


def test_lateral_motion_makes_a_lane_change_the_likely_mode():
    heading = -math.atan2(1.5, 20.0)  # drifting right at 1.5 m/s: a cut-in into y = 0
    p = predict(straight_road(), [(30.0, 3.6, heading, math.hypot(20.0, 1.5))])
    assert p.model[0] == "right" and p.mode_prob[0] > 0.5
    assert (np.diff(p.mode_prob) <= 0.0).all() and p.mode_prob.sum() <= 1.0 + 1e-9
    right = p.model.index("right")
    assert abs(p.y_m[right, -1]) < 0.05  # ends on the centre of the lane it changes into
    assert (np.diff(p.y_m[right]) <= 1e-9).all()  # moving monotonically across


def test_the_lane_change_probability_grows_with_lateral_speed_and_offset():
    def p_right(lat_speed, y):
        h = -math.atan2(lat_speed, 20.0)
        return modes(predict(straight_road(), [(30.0, y, h, 20.0)])).get("right", 0.0)

    assert p_right(0.0, 4.0) < p_right(0.5, 4.0) < p_right(1.0, 4.0) < p_right(1.0, 3.2)


def test_no_lane_change_towards_a_side_without_a_lane():
    h = -math.atan2(1.5, 20.0)  # drifting right in the rightmost lane
    assert "right" not in predict(straight_road(), [(30.0, -4.0, h, 20.0)]).model


def test_a_car_off_every_lane_gets_constant_velocity():
    p = predict(straight_road(), [(30.0, 20.0, 0.0, 10.0)])
    assert p.model == ["cv"] and p.mode_prob.tolist() == [1.0]
    assert np.allclose(p.x_m[0, -1], 60.0) and np.allclose(p.y_m[0], 20.0)


def test_the_lane_is_chosen_by_heading_where_lanes_cross():
    p = predict(crossing_road(), [(0.4, 0.3, 0.0, 10.0), (0.3, 0.4, math.pi / 2, 10.0)])
    first = [i for i, k in enumerate(p.track_id) if k == 1][0]
    second = [i for i, k in enumerate(p.track_id) if k == 2][0]
    assert p.model[first] == "lane" and p.model[second] == "lane"
    assert np.allclose(p.y_m[first], 0.0) and p.x_m[first, -1] > 29.0  # east along y = 0
    assert np.allclose(p.x_m[second], 0.0) and p.y_m[second, -1] > 29.0  # north along x = 0


@pytest.mark.parametrize(("y0", "heading_offset", "likely"), [
    (-40.0, 0.0, None),  # far before the branch: no evidence either way
    (-3.0, 0.0, "straight"),  # at the branch, still heading straight: straight on
    (1.5, 0.35, "left"),  # already turning left
])
def test_lane_continuations_share_the_keeping_probability_by_heading(y0, heading_offset, likely):
    p = predict(branching_road(), [(-0.1 if y0 > 0 else 0.0, y0, math.pi / 2 + heading_offset,
                                    10.0)])
    lanes = [i for i, m in enumerate(p.model) if m == "lane"]
    if likely is None:  # two continuations, equally likely (both still on the approach)
        assert len(lanes) == 2 and abs(p.mode_prob[lanes[0]] - p.mode_prob[lanes[1]]) < 0.05
    else:
        prob = {("left" if p.x_m[i, -1] < -5.0 else "straight"): p.mode_prob[i] for i in lanes}
        assert max(prob, key=prob.get) == likely and prob[likely] > 0.7


def test_a_left_turn_is_predicted_along_the_turn_into_the_exit():
    p = predict(branching_road(), [(-0.5, 2.0, math.pi / 2 + 0.4, 10.0)])
    left = p.mode_prob.argmax()
    assert p.x_m[left, -1] < -15.0 and np.isclose(p.y_m[left, -1], 15.0, atol=0.2)


def test_no_obstacles_gives_empty_predictions():
    p = predict(straight_road(), [])
    assert p.x_m.shape == (0, 30) and p.model == [] and len(p.track_id) == 0
    assert p.mode_prob.shape == (0,)


def test_a_map_without_lanes_predicts_constant_velocity():
    road = straight_road()
    bare = type(road)(name="bare", lanes=(), route=road.route)
    p = predict(bare, [(30.0, 0.0, 0.0, 10.0)])
    assert p.model == ["cv"] and np.allclose(p.x_m[0, -1], 60.0)
