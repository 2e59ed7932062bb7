"""Planning: following, ignoring the adjacent lane, gap acceptance and emergency braking."""

import math

import numpy as np
from conftest import crossing_road, cv_predictions, ego_at, straight_road

from evoeye.ads import ADSConfig
from evoeye.ads.messages import PLANNING_DECISIONS
from evoeye.ads.planning import RoutePlanner

NORTH = math.pi / 2


def plan(road, ego, rows, cruise=20.0):
    planner = RoutePlanner(road, ADSConfig.cautious().planning, cruise, 0.05)
    return planner.plan(cv_predictions(rows), ego)


def test_the_plan_runs_along_the_route_from_the_ego():
    p = plan(straight_road(), ego_at(10.0, 0.6, 0.0, 20.0), [])
    assert p.decision == "cruise" and p.leader_track_id == -1
    assert len(p.t_rel_s) == 41 and math.isclose(p.t_rel_s[-1], 4.0)
    assert np.allclose(p.y_m, 0.0) and math.isclose(p.x_m[0], 10.0, abs_tol=1e-9)
    assert np.allclose(np.diff(p.x_m), 2.0, atol=0.05)  # 20 m/s for 0.1 s
    assert np.allclose(p.heading_rad, 0.0) and np.allclose(p.speed_mps, 20.0)


def test_brakes_for_a_stopped_car_ahead_in_the_lane():
    p = plan(straight_road(), ego_at(0.0, 0.0, 0.0, 20.0), [(60.0, 0.0, 0.0, 0.0)])
    assert p.decision in ("follow", "emergency_brake") and p.leader_track_id == 1
    assert p.accel_mps2[0] < -1.0 and p.speed_mps[-1] < p.speed_mps[0]


def test_ignores_a_stopped_car_in_the_adjacent_lane():
    p = plan(straight_road(), ego_at(0.0, 0.0, 0.0, 20.0), [(30.0, 4.0, 0.0, 0.0)])
    assert p.decision == "cruise" and p.accel_mps2[0] >= 0.0


def test_emergency_brakes_when_the_time_to_collision_is_short():
    p = plan(straight_road(), ego_at(0.0, 0.0, 0.0, 20.0), [(15.0, 0.0, 0.0, 0.0)])
    assert p.decision == "emergency_brake" and p.accel_mps2[0] == -8.0


def test_follows_a_car_cutting_in_once_its_prediction_enters_the_path():
    heading = -math.atan2(1.5, 18.0)
    p = plan(straight_road(), ego_at(0.0, 0.0, 0.0, 20.0), [(25.0, 3.5, heading, 18.06)])
    assert p.decision == "follow" and p.leader_track_id == 1 and p.accel_mps2[0] < 0.0


def test_yields_to_a_crossing_car_arriving_at_the_same_time():
    p = plan(crossing_road(), ego_at(0.0, -27.0, NORTH, 9.0), [(-27.0, 0.0, 0.0, 9.0)], cruise=9.0)
    assert p.decision == "yield" and p.leader_track_id == 1
    assert p.accel_mps2[0] < 0.0
    # stopping before the conflict region: the plan never reaches the crossing lane
    assert p.y_m[-1] < -1.0 - 2.5


def test_proceeds_when_the_crossing_car_comes_after_the_ego_has_cleared():
    p = plan(crossing_road(), ego_at(0.0, -12.0, NORTH, 9.0), [(-28.0, 0.0, 0.0, 9.0)], cruise=9.0)
    assert p.decision == "proceed" and p.accel_mps2[0] >= 0.0


def test_ignores_a_crossing_car_that_is_far_away():
    p = plan(crossing_road(), ego_at(0.0, -27.0, NORTH, 9.0), [(-150.0, 0.0, 0.0, 9.0)], cruise=9.0)
    assert p.decision == "cruise" and p.accel_mps2[0] >= 0.0


def test_ignores_oncoming_traffic_in_its_own_lane():
    p = plan(crossing_road(), ego_at(0.0, -60.0, NORTH, 9.0), [(-4.0, -20.0, -NORTH, 9.0)], 9.0)
    assert p.decision == "cruise"


def test_outputs_are_finite_and_decisions_known():
    road = crossing_road()
    planner = RoutePlanner(road, ADSConfig.cautious().planning, 9.0, 0.05)
    rng = np.random.default_rng(0)
    for _ in range(50):
        rows = [(rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(-math.pi, math.pi),
                 rng.uniform(0, 12)) for _ in range(rng.integers(0, 7))]
        p = planner.plan(cv_predictions(rows), ego_at(0.0, rng.uniform(-40, 0), NORTH,
                                                      rng.uniform(0, 12)))
        assert p.decision in PLANNING_DECISIONS
        for a in (p.x_m, p.y_m, p.heading_rad, p.speed_mps, p.accel_mps2):
            assert np.isfinite(a).all()
        assert (p.speed_mps >= 0.0).all()
