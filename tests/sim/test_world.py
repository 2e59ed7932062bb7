"""The highway-env world and the scripted NPCs, stepped without the ADS."""

import numpy as np
import pytest

from evoeye.scenarios import get_scenario
from evoeye.sim.highway import EGO_LANE, build_highway
from evoeye.sim.intersection import NPC_MOVES, build_intersection

DT = 0.05
HIGHWAY = get_scenario("highway-cut-in")
CROSSING = get_scenario("unprotected-intersection")
LANE_W = 4.0


def highway_params(**overrides):
    """A calm highway: everyone far away and slow to act, except what a test overrides."""
    p = HIGHWAY.as_dict(HIGHWAY.low)
    p.update(ego_speed_mps=25.0, lead_gap_m=70.0, lead_speed_mps=25.0, lead_brake_time_s=16.0,
             lead_brake_decel_mps2=0.0, left_cutin_trigger_gap_m=2.0, right_cutin_trigger_gap_m=2.0,
             left_cutin_gap_m=40.0, right_cutin_gap_m=40.0, left_cutin_speed_mps=32.0,
             right_cutin_speed_mps=32.0, left_follow_gap_m=-60.0,
             right_follow_gap_m=-60.0, overtaker_gap_m=-80.0, overtaker_speed_mps=25.0)
    p.update(overrides)
    return HIGHWAY.as_dict(HIGHWAY.from_dict(p))


def run(world, seconds, accel=0.0, steer=0.0):
    """Step `seconds` with a fixed ego command; return the scenes, one per frame."""
    scenes = []
    for _ in range(int(round(seconds / DT))):
        scenes.append(world.scene())
        world.step(accel, steer, DT)
    return scenes


def actor_track(scenes, actor_id, field):
    return np.array([getattr(s, field)[list(s.actor_id).index(actor_id)] for s in scenes
                     if actor_id in s.actor_id])


def test_lead_vehicle_brakes_as_scripted():
    p = highway_params(lead_brake_time_s=3.0, lead_brake_decel_mps2=6.0, lead_brake_duration_s=2.0)
    world, cruise = build_highway(p, np.random.default_rng(0))
    assert cruise == p["ego_speed_mps"]
    scenes = run(world, 6.0, accel=-2.0)  # the ego slows so the lead stays free
    v = actor_track(scenes, 1, "speed_mps")
    t = np.array([s.t_s for s in scenes])
    before, after = v[np.searchsorted(t, 2.9)], v[np.searchsorted(t, 5.0)]
    assert before - after == pytest.approx(12.0, abs=1.5)  # 6 m/s² for 2 s
    a = actor_track(scenes, 1, "accel_mps2")
    assert a[np.searchsorted(t, 4.0)] == pytest.approx(-6.0, abs=0.5)


@pytest.mark.parametrize("side,lane_y", [("left", 0.0), ("right", 8.0)])
def test_cut_in_triggers_when_the_gap_to_the_ego_closes(side, lane_y):
    # the NPC starts 40 m ahead (centres), 5 m/s slower than the ego: its rear is 10 m ahead of
    # the ego's front after (40 - 5 - 10) / 5 = 5 s, when a 10 m trigger gap fires
    p = highway_params(**{f"{side}_cutin_trigger_gap_m": 10.0, f"{side}_cutin_duration_s": 1.5,
                          f"{side}_cutin_gap_m": 40.0, f"{side}_cutin_speed_mps": 20.0},
                       ego_speed_mps=25.0, lead_gap_m=70.0, lead_speed_mps=30.0)
    world, _ = build_highway(p, np.random.default_rng(0))
    actor = 2 if side == "left" else 3
    scenes = run(world, 9.0)
    y = actor_track(scenes, actor, "y_m")
    t = np.array([s.t_s for s in scenes])
    assert y[np.searchsorted(t, 4.8)] == pytest.approx(lane_y, abs=0.1)  # not before the trigger
    start = t[int(np.argmax(np.abs(y - lane_y) > 0.05))]
    assert start == pytest.approx(5.0, abs=0.3)
    assert y[np.searchsorted(t, 8.5)] == pytest.approx(EGO_LANE * LANE_W, abs=0.5)


def test_a_cut_in_never_fires_outside_its_trigger_window():
    p = highway_params(left_cutin_trigger_gap_m=5.0, left_cutin_gap_m=40.0,
                       left_cutin_speed_mps=30.0, ego_speed_mps=20.0)  # it only pulls away
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0)
    assert np.abs(actor_track(scenes, 2, "y_m")).max() < 0.05


def test_sharper_cut_in_reaches_the_lane_sooner():
    def time_to_enter(duration):
        p = highway_params(left_cutin_trigger_gap_m=20.0, left_cutin_duration_s=duration,
                           left_cutin_gap_m=20.0, left_cutin_speed_mps=25.0)
        scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0)
        y = actor_track(scenes, 2, "y_m")
        return scenes[int(np.argmax(y > EGO_LANE * LANE_W - 1.0))].t_s

    assert time_to_enter(0.8) < time_to_enter(3.0) - 0.5


def test_overtaker_cuts_back_once_ahead_of_the_ego():
    p = highway_params(overtaker_gap_m=-30.0, overtaker_speed_mps=36.0, ego_speed_mps=22.0,
                       left_follow_gap_m=80.0, left_follow_speed_mps=33.0,
                       left_cutin_gap_m=40.0, left_cutin_speed_mps=32.0)  # a free left lane
    world, _ = build_highway(p, np.random.default_rng(0))
    scenes = run(world, 10.0)
    x_rel = actor_track(scenes, 6, "x_m") - np.array([s.x_m[0] for s in scenes])
    y = actor_track(scenes, 6, "y_m")
    assert y[0] == pytest.approx(0.0, abs=0.1)
    assert y[-1] == pytest.approx(EGO_LANE * LANE_W, abs=0.5)
    first_move = int(np.argmax(y > 0.3))
    assert x_rel[first_move] >= 12.0 - 1.0  # it waited until it was ahead


def test_ego_runs_into_a_stopped_lead_and_the_partner_is_recorded():
    p = highway_params(lead_gap_m=20.0, lead_brake_time_s=2.0, lead_brake_decel_mps2=8.0,
                       lead_brake_duration_s=5.0, lead_speed_mps=20.0, ego_speed_mps=28.0)
    world, _ = build_highway(p, np.random.default_rng(0))
    scenes = run(world, 8.0)
    hit = [s for s in scenes if s.ego_collision]
    assert hit, "the ego never collided"
    assert hit[0].collision_actor == 1
    assert not any(s.ego_collision for s in scenes[: scenes.index(hit[0])])


def test_a_blocked_vehicle_stops_and_never_reverses():
    p = highway_params(lead_gap_m=15.0, lead_speed_mps=20.0, lead_brake_time_s=2.0,
                       lead_brake_decel_mps2=8.0, lead_brake_duration_s=5.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0, accel=-8.0)
    speeds = np.concatenate([s.speed_mps for s in scenes])
    assert speeds.min() == 0.0  # someone came to a standstill, and nobody went below it


def test_npcs_pass_through_each_other_but_not_through_the_ego():
    world, _ = build_highway(highway_params(), np.random.default_rng(0))
    ego, a, b = (act.vehicle for act in world.active[:3])
    a.position = ego.position + np.array([30.0, 0.0])
    b.position = ego.position + np.array([31.0, 0.0])  # two NPCs on top of each other
    world.step(0.0, 0.0, DT)
    assert not world.scene().crashed.any()
    b.position = ego.position + np.array([1.0, 0.0])  # an NPC on top of the ego
    world.step(0.0, 0.0, DT)
    scene = world.scene()
    assert scene.ego_collision and scene.collision_actor == world.active[2].actor_id


def test_an_npc_may_spawn_beside_the_ego_in_the_next_lane():
    p = highway_params(right_cutin_gap_m=0.0)  # alongside the ego, one lane to the right
    world, _ = build_highway(p, np.random.default_rng(0))
    assert 3 in world.scene().actor_id


def test_same_params_and_seed_give_the_same_world():
    x = HIGHWAY.sample(np.random.default_rng(9))
    a = run(build_highway(HIGHWAY.as_dict(x), np.random.default_rng(4))[0], 5.0, accel=0.5)
    b = run(build_highway(HIGHWAY.as_dict(x), np.random.default_rng(4))[0], 5.0, accel=0.5)
    for sa, sb in zip(a, b, strict=True):
        np.testing.assert_array_equal(sa.x_m, sb.x_m)
        np.testing.assert_array_equal(sa.speed_mps, sb.speed_mps)


def test_intersection_npcs_appear_at_their_start_time_and_follow_their_route():
    p = CROSSING.as_dict(CROSSING.low)
    p.update(cross_east_start_s=3.0, cross_east_speed_mps=10.0, opp_left_start_s=0.0,
             cross_west_start_s=4.0, right_merge_start_s=4.0, left_merge_start_s=4.0)
    world, _ = build_intersection(CROSSING.as_dict(CROSSING.from_dict(p)), np.random.default_rng(0))
    scenes = run(world, 12.0, accel=-3.0)  # the ego stays out of the way
    east = list(NPC_MOVES).index("cross_east") + 1
    present = [s.t_s for s in scenes if east in s.actor_id]
    assert present[0] == pytest.approx(3.0, abs=DT)
    x = actor_track(scenes, east, "x_m")
    y = actor_track(scenes, east, "y_m")
    assert x[0] > 30 and x[-1] < -12  # east → west, through the box (|x| < 11 m) and out
    assert np.abs(y + 2.0).max() < 0.5  # on the westbound lane all the way


def test_npcs_from_one_approach_never_spawn_on_top_of_each_other():
    p = CROSSING.as_dict(CROSSING.low)
    p.update(cross_west_start_s=1.0, left_merge_start_s=1.0)  # both from the west at t = 1 s
    world, _ = build_intersection(CROSSING.as_dict(CROSSING.from_dict(p)), np.random.default_rng(0))
    scenes = run(world, 6.0, accel=-3.0)
    west, merge = list(NPC_MOVES).index("cross_west") + 1, list(NPC_MOVES).index("left_merge") + 1
    both = [s for s in scenes if west in s.actor_id and merge in s.actor_id]
    assert both, "the second NPC never appeared"
    s = both[0]
    i, j = list(s.actor_id).index(west), list(s.actor_id).index(merge)
    assert np.hypot(s.x_m[i] - s.x_m[j], s.y_m[i] - s.y_m[j]) >= 8.0
    assert not any(s.crashed[1:].any() for s in scenes)
