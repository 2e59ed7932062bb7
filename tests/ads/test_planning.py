"""Planning: following, ignoring the adjacent lane, gap acceptance and emergency braking."""

import math
from dataclasses import replace

import numpy as np
import pytest
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


def test_emergency_braking_ramps_up_at_its_jerk_to_its_limit():
    config = ADSConfig.cautious().planning
    planner = RoutePlanner(straight_road(), config, 20.0, 0.05)
    accel = []
    for _ in range(8):
        p = planner.plan(cv_predictions([(15.0, 0.0, 0.0, 0.0)]), ego_at(0.0, 0.0, 0.0, 20.0))
        assert p.decision == "emergency_brake"
        accel.append(p.accel_mps2[0])
    step = config.emergency_jerk_mps3 * 0.05
    assert np.allclose(np.diff(accel)[:4], -step) and math.isclose(accel[0], -step)
    assert accel[-1] == -config.emergency_decel_mps2


def test_normal_decisions_brake_no_harder_than_the_comfort_limit():
    config = ADSConfig.cautious().planning
    p = plan(straight_road(), ego_at(0.0, 0.0, 0.0, 20.0), [(45.0, 0.0, 0.0, 0.0)])
    assert p.decision == "follow" and p.accel_mps2[0] == -config.comfort_decel_mps2


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
    p = plan(crossing_road(), ego_at(0.0, -6.0, NORTH, 9.0), [(-28.0, 0.0, 0.0, 9.0)], cruise=9.0)
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


def predictions_with_modes(rows, probs):
    """One track (id 1) with a mode per row (constant velocity), probabilities `probs`."""
    p = cv_predictions(rows)
    return type(p)(t_s=p.t_s, dt_s=p.dt_s, track_id=np.ones(len(rows), dtype=np.int64),
                   model=["lane"] * len(rows), mode_prob=np.asarray(probs, dtype=float),
                   length_m=p.length_m, width_m=p.width_m, x_m=p.x_m, y_m=p.y_m)


@pytest.mark.parametrize(("p_cross", "decision"), [(0.1, "cruise"), (0.3, "yield")])
def test_plans_against_every_mode_above_the_probability_threshold(p_cross, decision):
    """The car is most likely turning away (it stays parallel, off the path), but may cross."""
    rows = [(-27.0, -4.0, 0.0, 0.0), (-27.0, 0.0, 0.0, 9.0)]
    planner = RoutePlanner(crossing_road(), ADSConfig.cautious().planning, 9.0, 0.05)
    p = planner.plan(predictions_with_modes(rows, [1.0 - p_cross, p_cross]),
                     ego_at(0.0, -27.0, NORTH, 9.0))
    assert p.decision == decision


def test_a_yield_is_held_until_the_conflict_has_been_clear_for_a_while():
    config = ADSConfig.cautious().planning
    planner = RoutePlanner(crossing_road(), config, 9.0, 0.05)
    ego = ego_at(0.0, -27.0, NORTH, 9.0)
    first = planner.plan(cv_predictions([(-27.0, 0.0, 0.0, 9.0)]), ego)
    assert first.decision == "yield"
    after = [planner.plan(cv_predictions([]), ego) for _ in range(config.release_frames + 1)]
    held = [p.decision for p in after]
    assert held[: config.release_frames - 1] == ["yield"] * (config.release_frames - 1)
    assert held[-1] == "cruise"
    assert all(p.accel_mps2[0] < 0.0 for p in after[: config.release_frames - 1])
    assert all(p.leader_track_id == 1 for p in after[: config.release_frames - 1])


def test_an_emergency_brake_is_held_through_a_flicker_of_the_track():
    config = ADSConfig.cautious().planning
    planner = RoutePlanner(straight_road(), config, 20.0, 0.05)
    ego = ego_at(0.0, 0.0, 0.0, 20.0)
    assert planner.plan(cv_predictions([(15.0, 0.0, 0.0, 0.0)]), ego).decision == "emergency_brake"
    flicker = planner.plan(cv_predictions([]), ego)
    assert flicker.decision == "emergency_brake" and flicker.accel_mps2[0] < 0.0


def test_a_proceed_is_not_revoked_for_a_marginal_change():
    """The crossing car passes first; the ego proceeds if it arrives after the car has left."""
    config = replace(ADSConfig().planning, yield_decel_max_mps2=3.0)
    ego = ego_at(0.0, -30.0, NORTH, 9.0)

    def decide(planner, x_car):
        return planner.plan(cv_predictions([(x_car, 0.0, 0.0, 9.0)]), ego).decision

    # where a fresh planner switches from proceed to yield as the car starts farther away
    xs = np.arange(-5.0, -30.0, -0.25)
    fresh = [decide(RoutePlanner(crossing_road(), config, 9.0, 0.05), x) for x in xs]
    k = fresh.index("yield")
    assert k > 0 and fresh[k - 1] == "proceed"
    committed = RoutePlanner(crossing_road(), config, 9.0, 0.05)
    assert decide(committed, xs[k - 1]) == "proceed"
    assert decide(committed, xs[k]) == "proceed"  # marginally later: still proceeds
    clearly = xs[k] - 9.0 * config.proceed_hold_margin_s - 1.0
    assert decide(committed, clearly) == "yield"  # clearly later: yields
