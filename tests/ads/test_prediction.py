"""Prediction: lane keeping, lane changes and lane continuations with probabilities; CV off-lane."""

import math

import numpy as np
import pytest
from conftest import (
    LANE_W_M,
    crossing_road,
    curved_road,
    ego_at,
    lane,
    obstacles,
    polyline,
    straight_road,
)

from evoeye.ads import ADSConfig
from evoeye.ads.prediction import IntentPredictor
from evoeye.scene import Lane, RoadMap

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
    heading = -math.atan2(2.0, 20.0)  # a quarter into the change, drifting right at 2 m/s
    p = predict(straight_road(), [(30.0, 3.0, heading, math.hypot(20.0, 2.0))])
    assert p.model[0] == "right" and p.mode_prob[0] > 0.5
    assert (np.diff(p.mode_prob) <= 0.0).all() and p.mode_prob.sum() <= 1.0 + 1e-9
    right = p.model.index("right")
    assert abs(p.y_m[right, -1]) < 0.05  # ends on the centre of the lane it changes into
    assert (np.diff(p.y_m[right]) <= 1e-9).all()  # moving monotonically across


def test_the_lane_change_probability_grows_with_lateral_speed_and_offset():
    def p_right(lat_speed, y):
        h = -math.atan2(lat_speed, 20.0)
        return modes(predict(straight_road(), [(30.0, y, h, 20.0)])).get("right", 0.0)

    assert p_right(1.0, 4.0) < p_right(1.5, 4.0) < p_right(2.0, 4.0) < p_right(2.0, 3.2)


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


def give_way_road() -> RoadMap:
    """The route goes north along x = 0; a minor road from the west ends at (−6, 0), where its
    traffic gives way to the route's, and goes on east across it."""
    north = lane("north", polyline(0.0, -200.0, math.pi / 2, 400.0))
    minor = Lane("minor", polyline(-106.0, 0.0, 0.0, 100.0), LANE_W_M, 30.0,
                 yields_to_route=True)
    across = lane("across", polyline(-6.0, 0.0, 0.0, 100.0))
    return RoadMap(name="give-way", lanes=(north, minor, across), route=north)



def test_a_car_that_can_still_stop_where_its_lane_gives_way_is_expected_to():
    # 40 m before its stop line at 10 m/s: stopping needs 1.25 m/s², well within a yield
    p = predict(give_way_road(), [(-46.0, 0.0, 0.0, 10.0)])
    m = modes(p)
    c = ADSConfig().prediction
    need = 10.0**2 / (2.0 * 40.0)
    fade = math.exp((need - c.yield_decel_mps2) / c.yield_decel_scale_mps2)
    expected = c.yield_prior / (1.0 + fade)
    assert p.model[0] == "yield" and m["yield"] == pytest.approx(expected, abs=0.01)
    k = p.model.index("yield")
    t = (np.arange(30) + 1) * 0.1  # it brakes evenly to a stop at the end of its lane …
    assert np.allclose(p.x_m[k], -46.0 + 10.0 * t - 0.5 * need * t * t, atol=0.6)
    assert np.all(np.diff(np.diff(p.x_m[k])) < 0.0) and np.allclose(p.y_m[k], 0.0, atol=1e-6)
    go = [j for j, name in enumerate(p.model) if name == "lane"]
    assert go and p.x_m[go[0], -1] == pytest.approx(-16.0, abs=0.5)  # … or keeps its speed


def test_a_yielding_car_is_predicted_to_stand_at_its_stop_line():
    p = predict(give_way_road(), [(-14.0, 0.0, 0.0, 5.0)])  # 8 m out at 5 m/s: stops in 3.2 s
    k = p.model.index("yield")
    assert p.x_m[k, -1] == pytest.approx(-6.0, abs=0.3) and p.x_m[k].max() <= -6.0 + 0.3


def test_a_car_too_fast_to_stop_where_its_lane_gives_way_is_expected_to_go_on():
    # 8 m before the line at 12 m/s: stopping would need 9 m/s², no driver who means to
    # stop leaves it that late
    p = predict(give_way_road(), [(-14.0, 0.0, 0.0, 12.0)])
    m = modes(p)
    assert p.model[0] == "lane" and m.get("yield", 0.0) < 0.01


def test_the_give_way_belief_fades_with_the_braking_stopping_would_need():
    c = ADSConfig().prediction
    probs = []
    for share in (0.3, 0.6, 0.85, 1.0, 1.4):  # the braking a stop needs, over the limit
        to_line_m = 10.0**2 / (2.0 * share * c.yield_decel_mps2)
        m = modes(predict(give_way_road(), [(-6.0 - to_line_m, 0.0, 0.0, 10.0)]))
        probs.append(m.get("yield", 0.0))
    assert probs == sorted(probs, reverse=True) and probs[0] > 0.85 and probs[-1] < 0.2
    assert 0.1 < probs[3] < 0.8  # around the limit: either is plausible


def test_no_give_way_hypothesis_on_a_lane_with_the_right_of_way():
    p = predict(crossing_road(), [(-30.0, 0.0, 0.0, 10.0)])
    assert "yield" not in p.model
