"""The world stepped without the ADS: NPCs that drive like cars, scripts on relative state."""

import numpy as np
import pytest

from evoeye.scenarios import get_scenario
from evoeye.sim.highway import EGO_LANE, build_highway
from evoeye.sim.intersection import EGO_APPROACH_M, NPC_MOVES, _box_entry_s, build_intersection

DT = 0.05
HIGHWAY = get_scenario("highway-cut-in")
CROSSING = get_scenario("unprotected-intersection")
LANE_W = 4.0


def highway_params(**overrides):
    """A calm highway: everyone far away and slow to act, except what a test overrides. The
    world's mechanics are tested beyond the catalog's ranges (a cut-in from behind, a lead that
    never brakes), so the values are not checked against them."""
    p = HIGHWAY.as_dict(HIGHWAY.low)
    p.update(ego_speed_mps=25.0, lead_gap_m=70.0, lead_speed_mps=25.0, lead_brake_time_s=16.0,
             lead_brake_decel_mps2=0.0, left_cutin_trigger_gap_m=2.0, right_cutin_trigger_gap_m=2.0,
             left_cutin_gap_m=60.0, right_cutin_gap_m=60.0, left_cutin_speed_mps=30.0,
             right_cutin_speed_mps=30.0, left_follow_gap_m=-60.0,
             right_follow_gap_m=-60.0, overtaker_gap_m=-80.0, overtaker_speed_mps=25.0)
    p.update(overrides)
    assert p.keys() == set(HIGHWAY.names)
    return p


def crossing_params(**overrides):
    """The middle of the intersection's space, except what a test overrides (unchecked against
    the catalog's ranges, as for highway_params)."""
    p = CROSSING.as_dict((CROSSING.low + CROSSING.high) / 2.0)
    p.update(overrides)
    assert p.keys() == set(CROSSING.names)
    return p


def run(world, seconds, accel=0.0, steer=0.0):
    """Step `seconds` with an ego command (a fixed accel, or a function of the scene); return
    the scenes, one per frame."""
    scenes = []
    for _ in range(int(round(seconds / DT))):
        scenes.append(world.scene())
        world.step(accel(scenes[-1]) if callable(accel) else accel, steer, DT)
    return scenes


def make_room(scene):
    """An ego that brakes once anyone moves towards its lane, so a cut-in is never hit."""
    off = np.abs(scene.y_m[1:] - EGO_LANE * LANE_W)
    return -4.0 if ((off > 1e-9) & (off < LANE_W - 1e-9)).any() else 0.0


def track(scenes, actor_id, field):
    return np.array([getattr(s, field)[actor_id] for s in scenes])


def times(scenes):
    return np.array([s.t_s for s in scenes])


def lateral_kinematics(scenes, actor_id, road_heading=None):
    """(|lateral speed| to the road, |a_lat|, |a_lon|) over 0.15 s, as the audit measures."""
    h, v = track(scenes, actor_id, "heading_rad"), track(scenes, actor_id, "speed_mps")
    vx, vy = v * np.cos(h), v * np.sin(h)
    k = 3
    ax, ay = (vx[k:] - vx[:-k]) / (k * DT), (vy[k:] - vy[:-k]) / (k * DT)
    c, s = np.cos(h[:-k]), np.sin(h[:-k])
    lat_v = np.abs(vy) if road_heading is None else None
    return lat_v, np.abs(-ax * s + ay * c), np.abs(ax * c + ay * s)


def test_lead_vehicle_brakes_as_scripted():
    p = highway_params(lead_brake_time_s=3.0, lead_brake_decel_mps2=6.0, lead_brake_duration_s=2.0)
    world, cruise = build_highway(p, np.random.default_rng(0))
    assert cruise == p["ego_speed_mps"]
    scenes = run(world, 6.0, accel=-2.0)  # the ego slows so the lead stays free
    v, t = track(scenes, 1, "speed_mps"), times(scenes)
    assert v[0] == pytest.approx(p["ego_speed_mps"])  # it starts at the ego's speed
    before, after = v[np.searchsorted(t, 2.9)], v[np.searchsorted(t, 5.0)]
    assert before - after == pytest.approx(12.0, abs=1.5)  # 6 m/s² for 2 s
    assert track(scenes, 1, "accel_mps2")[np.searchsorted(t, 4.0)] == pytest.approx(-6.0, abs=0.3)


@pytest.mark.parametrize("side,lane_y,actor", [("left", 0.0, 2), ("right", 8.0, 3)])
def test_a_slower_cut_in_ahead_fires_when_the_gap_closes_to_its_trigger(side, lane_y, actor):
    # centre 40 m ahead, 5 m/s slower: its bumper gap (35 m) falls to 15 m after 4 s, when the
    # ego is 3 s away (at least CUT_IN_MIN_TTC_S)
    p = highway_params(**{f"{side}_cutin_trigger_gap_m": 15.0, f"{side}_cutin_duration_s": 3.0,
                          f"{side}_cutin_gap_m": 40.0, f"{side}_cutin_speed_mps": 20.0},
                       lead_gap_m=70.0, lead_speed_mps=30.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 10.0, accel=make_room)
    y, t = track(scenes, actor, "y_m"), times(scenes)
    start = t[int(np.argmax(np.abs(y - lane_y) > 1e-9))]
    assert start == pytest.approx(4.0, abs=0.2)
    assert y[np.searchsorted(t, start + 3.1)] == pytest.approx(EGO_LANE * LANE_W, abs=0.05)


def test_a_faster_cut_in_from_behind_fires_at_its_trigger_gap_not_at_zero():
    p = highway_params(left_cutin_trigger_gap_m=15.0, left_cutin_duration_s=3.0,
                       left_cutin_gap_m=-20.0, left_cutin_speed_mps=30.0, ego_speed_mps=22.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0)
    y = track(scenes, 2, "y_m")
    k = int(np.argmax(y > 1e-9))
    assert k > 0
    bumper_gap = scenes[k].x_m[2] - scenes[k].x_m[0] - 5.0
    assert bumper_gap == pytest.approx(15.0, abs=1.0)  # a frame at 10 m/s closing is 0.5 m


def test_a_cut_in_waits_while_the_ego_would_reach_it_too_soon():
    # trigger at 5 m with the ego closing at 10 m/s: 0.5 s to contact, so it holds its lane
    p = highway_params(left_cutin_trigger_gap_m=5.0, left_cutin_gap_m=30.0,
                       left_cutin_speed_mps=15.0, ego_speed_mps=25.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 6.0)
    assert np.abs(track(scenes, 2, "y_m")).max() < 1e-9


def test_a_cut_in_never_fires_if_its_trigger_gap_is_never_crossed():
    p = highway_params(left_cutin_trigger_gap_m=5.0, left_cutin_gap_m=40.0,
                       left_cutin_speed_mps=30.0, ego_speed_mps=20.0)  # it only pulls away
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0)
    assert np.abs(track(scenes, 2, "y_m")).max() < 1e-9


@pytest.mark.parametrize("duration_s", [2.6, 3.5, 5.0])
def test_lane_changes_stay_within_the_lateral_bounds(duration_s):
    p = highway_params(left_cutin_trigger_gap_m=15.0, left_cutin_duration_s=duration_s,
                       left_cutin_gap_m=40.0, left_cutin_speed_mps=20.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 12.0, accel=make_room)
    lat_v, a_lat, _ = lateral_kinematics(scenes, 2)
    assert np.abs(track(scenes, 2, "y_m")).max() > 3.9  # the change happened
    assert lat_v.max() <= 2.5
    assert a_lat.max() <= 4.0


def test_sharper_cut_in_reaches_the_lane_sooner():
    def time_to_enter(duration):
        p = highway_params(left_cutin_trigger_gap_m=15.0, left_cutin_duration_s=duration,
                           left_cutin_gap_m=40.0, left_cutin_speed_mps=20.0)
        scenes = run(build_highway(p, np.random.default_rng(0))[0], 12.0, accel=make_room)
        return scenes[int(np.argmax(track(scenes, 2, "y_m") > EGO_LANE * LANE_W - 1.0))].t_s

    assert time_to_enter(2.6) < time_to_enter(5.0) - 1.0


def test_a_cut_in_waits_for_a_gap_the_lead_leaves_it():
    # the lead sits right where the cut-in would land: it must not change lanes onto it
    p = highway_params(left_cutin_trigger_gap_m=15.0, left_cutin_gap_m=40.0,
                       left_cutin_speed_mps=20.0, lead_gap_m=30.0, lead_speed_mps=20.0,
                       ego_speed_mps=20.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0, accel=0.0)
    assert not any(s.crashed[1:].any() for s in scenes)
    y, x_lead, x_cut = track(scenes, 2, "y_m"), track(scenes, 1, "x_m"), track(scenes, 2, "x_m")
    moving = np.abs(y) > 0.01
    assert not (moving & (np.abs(x_cut - x_lead) < 5.0 + 5.0 + 10.0)).any()


def test_overtaker_cuts_back_once_ahead_of_the_ego():
    p = highway_params(overtaker_gap_m=-30.0, overtaker_speed_mps=36.0, ego_speed_mps=22.0,
                       left_follow_gap_m=80.0, left_follow_speed_mps=33.0,
                       left_cutin_gap_m=60.0, left_cutin_speed_mps=30.0)  # a free left lane
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 12.0)
    x_rel = track(scenes, 6, "x_m") - track(scenes, 0, "x_m")
    y = track(scenes, 6, "y_m")
    assert y[0] == pytest.approx(0.0, abs=1e-9)
    assert y[-1] == pytest.approx(EGO_LANE * LANE_W, abs=0.05)
    first_move = int(np.argmax(y > 1e-9))
    assert x_rel[first_move] - 5.0 == pytest.approx(12.0, abs=1.0)  # at its bumper gap


def test_npcs_follow_the_vehicle_ahead_instead_of_driving_through_it():
    # the overtaker (38 m/s) comes up behind a slow left-lane car (18 m/s) 40 m ahead of the
    # ego, while the ego keeps it from cutting back in front of it by staying level with it
    p = highway_params(left_follow_gap_m=40.0, left_follow_speed_mps=18.0, overtaker_gap_m=-15.0,
                       overtaker_speed_mps=38.0, left_cutin_gap_m=60.0, ego_speed_mps=20.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 15.0, accel=-1.0)
    assert not any(s.crashed.any() for s in scenes)
    gap = track(scenes, 4, "x_m") - track(scenes, 6, "x_m")
    same_lane = np.abs(track(scenes, 6, "y_m") - track(scenes, 4, "y_m")) < 2.0
    assert (gap[same_lane] > 5.0).all()  # always behind it, bumper to bumper
    assert track(scenes, 6, "speed_mps").min() < 20.0  # it slowed down for it


def test_ego_runs_into_a_stopped_lead_and_the_partner_is_recorded():
    p = highway_params(lead_gap_m=20.0, lead_brake_time_s=2.0, lead_brake_decel_mps2=6.5,
                       lead_brake_duration_s=5.0, lead_speed_mps=20.0, ego_speed_mps=28.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0)
    hit = [s for s in scenes if s.ego_collision]
    assert hit, "the ego never collided"
    assert hit[0].collision_actor == 1 and hit[0].crashed[1]
    assert not any(s.ego_collision for s in scenes[: scenes.index(hit[0])])


def test_a_blocked_vehicle_stops_and_never_reverses():
    p = highway_params(lead_gap_m=15.0, lead_speed_mps=20.0, lead_brake_time_s=2.0,
                       lead_brake_decel_mps2=6.5, lead_brake_duration_s=5.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 8.0, accel=-8.0)
    speeds = np.concatenate([s.speed_mps for s in scenes])
    assert speeds.min() == 0.0  # someone came to a standstill, and nobody went below it


def test_overlapping_npcs_are_a_recorded_contact_not_a_pass_through():
    world, _ = build_highway(highway_params(), np.random.default_rng(0))
    a, b = world.npcs[3], world.npcs[0]  # left follower, lead
    a.position[:] = world.ego.position + np.array([30.0, 0.0])
    b.position[:] = world.ego.position + np.array([31.0, 0.0])
    world._contacts()
    scene = world.scene()
    assert scene.crashed[[1, 4]].all() and not scene.ego_collision
    world.npcs[1].position[:] = world.ego.position + np.array([1.0, 0.0])
    world._contacts()
    scene = world.scene()
    assert scene.ego_collision and scene.collision_actor == 2


def test_same_params_and_seed_give_the_same_world():
    for space, build in ((HIGHWAY, build_highway), (CROSSING, build_intersection)):
        x = space.sample(np.random.default_rng(9))
        a = run(build(space.as_dict(x), np.random.default_rng(4))[0], 5.0, accel=0.5)
        b = run(build(space.as_dict(x), np.random.default_rng(4))[0], 5.0, accel=0.5)
        for sa, sb in zip(a, b, strict=True):
            np.testing.assert_array_equal(sa.x_m, sb.x_m)
            np.testing.assert_array_equal(sa.speed_mps, sb.speed_mps)


def test_every_intersection_actor_exists_from_the_start_and_the_ego_start_is_seeded():
    p = crossing_params()
    starts = []
    for seed in range(5):
        world, _ = build_intersection(p, np.random.default_rng(seed))
        scene = world.scene()
        assert scene.n == 1 + len(NPC_MOVES)
        starts.append(scene.y_m[0] - 11.0)  # the ego drives north (−y) to the box at y = 11
    assert all(EGO_APPROACH_M[0] - 1e-6 <= d <= EGO_APPROACH_M[1] + 1e-6 for d in starts)
    assert len(set(np.round(starts, 3))) == 5
    again = build_intersection(p, np.random.default_rng(0))[0].scene().y_m[0] - 11.0
    assert again == starts[0]


@pytest.mark.parametrize("name", list(NPC_MOVES))
def test_an_npc_meets_the_egos_path_offset_after_the_ego_would(name):
    from evoeye.sim.intersection import EGO_ROUTE, _conflict, _path

    offset = 1.5
    p = crossing_params(**{**{f"{n}_offset_s": 4.0 for n in NPC_MOVES}, f"{name}_offset_s": offset})
    world, cruise = build_intersection(p, np.random.default_rng(3))
    ego_path = _path(tuple(EGO_ROUTE))
    s_ego0, _ = ego_path.project(*world.ego.position)
    s_npc_c, s_ego_c = _conflict(*NPC_MOVES[name])
    t_ego = (s_ego_c - s_ego0) / cruise
    npc = world.npcs[list(NPC_MOVES).index(name)]
    t = 0.0
    while npc.s_m < s_npc_c and t < 40.0:  # the NPC alone, free road
        npc.advance(npc.longitudinal(np.inf, 0.0), DT)
        t += DT
    assert t - t_ego == pytest.approx(offset, abs=0.5)  # the start is planned on the profile


def test_intersection_npcs_slow_for_their_turns():
    p = crossing_params(**{f"{n}_speed_mps": 13.0 for n in NPC_MOVES})
    world, _ = build_intersection(p, np.random.default_rng(1))
    scenes = run(world, 20.0, accel=-5.0)  # the ego stays out of the way
    for actor in range(1, 6):
        pre = [k for k, s in enumerate(scenes) if not s.crashed[actor]]
        sub = [scenes[k] for k in pre]
        _, a_lat, a_lon = lateral_kinematics(sub, actor)
        assert a_lat.max() <= 4.5, actor  # "about 4": the profile is planned for 3
        assert a_lon.max() <= 9.0, actor


def test_box_entry_is_where_the_ego_route_enters_the_intersection():
    assert _box_entry_s() > 300.0


def test_npcs_settle_crossings_among_themselves():
    # every NPC timed to reach the ego's path at once: their own paths cross in the box too
    p = crossing_params(**{f"{n}_offset_s": 0.0 for n in NPC_MOVES},
                        **{f"{n}_speed_mps": 10.0 for n in NPC_MOVES})
    world, _ = build_intersection(p, np.random.default_rng(2))
    scenes = run(world, 35.0, accel=-5.0)  # the ego stops short of the box
    assert not any(s.crashed.any() for s in scenes)
    assert any(c.first is not None for c in world.conflicts)  # someone had to wait
    exits = [abs(s) > 15.0 for s in (scenes[-1].x_m[1:] + scenes[-1].y_m[1:])]
    assert all(exits)  # and everyone got through the box in the end


def test_a_fast_car_is_never_placed_just_behind_a_slow_one():
    p = highway_params(left_follow_gap_m=-20.0, left_follow_speed_mps=18.0,
                       overtaker_gap_m=-25.0, overtaker_speed_mps=38.0)
    scenes = run(build_highway(p, np.random.default_rng(0))[0], 6.0, accel=-1.0)
    assert not any(s.crashed.any() for s in scenes)
    assert scenes[0].x_m[4] - scenes[0].x_m[6] >= 9.0 + 20.0**2 / 6.0 - 1e-9


def test_a_turning_npc_yields_to_the_ego_unless_the_gap_is_long_enough():
    from evoeye.sim.intersection import _ego_crossing

    left = list(NPC_MOVES).index("opp_left") + 1
    s_cross = _ego_crossing(*NPC_MOVES["opp_left"])[0]

    def through_before_the_ego(ego_accel):
        late = {f"{n}_offset_s": 4.0 for n in NPC_MOVES}
        p = crossing_params(**{**late, "opp_left_offset_s": 0.0})
        world, _ = build_intersection(p, np.random.default_rng(5))
        for _ in range(int(25.0 / DT)):
            world.step(ego_accel if world.ego.speed > 0.0 else 0.0, 0.0, DT)
            npc = world.npcs[left - 1]
            if npc.s_m > s_cross:  # the NPC crossed the ego's path …
                return world.ego.position[1] > 0.0  # … with the ego not yet through the box
        return False

    assert not through_before_the_ego(0.0)  # the ego keeps coming: the NPC waits for it
    assert through_before_the_ego(-4.0)  # the ego stops short: the NPC goes first


def test_a_crossing_npc_brakes_for_a_car_blocking_its_way_after_a_reaction_time():
    from evoeye.sim.world import NPC_REACTION_S

    east = list(NPC_MOVES).index("cross_east") + 1
    late = {f"{n}_offset_s": 4.0 for n in NPC_MOVES}
    p = crossing_params(**{**late, "cross_east_offset_s": -2.0})
    world, _ = build_intersection(p, np.random.default_rng(5))
    npc = world.npcs[east - 1]
    while npc.position[0] > 30.0:  # park the ego across its way, 20 m ahead of it
        world.step(0.0, 0.0, DT)
    world.ego.position[:] = [npc.position[0] - 20.0, npc.position[1]]
    world.ego.heading, world.ego.speed = -np.pi / 2, 0.0
    v0, decel_at = npc.speed, None
    for k in range(int(3.0 / DT)):
        world.step(0.0, 0.0, DT)
        if decel_at is None and npc.accel_mps2 < -1.0:
            decel_at = (k + 1) * DT
    assert decel_at is not None and decel_at == pytest.approx(NPC_REACTION_S, abs=2 * DT)
    assert npc.speed < v0


def test_a_crashed_npc_slides_on_along_its_heading_to_a_standstill():
    world, _ = build_highway(highway_params(), np.random.default_rng(0))
    npc = world.npcs[1]
    npc.heading = 0.1  # as in the middle of a lane change
    npc.crashed = True
    x0, y0 = npc.position.copy()
    for _ in range(int(5.0 / DT)):
        world.step(0.0, 0.0, DT)
    assert npc.heading == 0.1 and npc.speed == 0.0
    dx, dy = npc.position - (x0, y0)
    assert dy / dx == pytest.approx(np.tan(0.1))


def test_a_turning_npc_stops_for_the_ego_standing_in_its_turn():
    # the ego stands with its nose in the opposing left-turner's arc; the turner (which goes,
    # since the ego has stopped) sees it along its arc and stops short instead of driving in
    from evoeye.sim.intersection import _ego_crossing

    left = list(NPC_MOVES).index("opp_left") + 1
    late = {f"{n}_offset_s": CROSSING.high[CROSSING.index(f"{n}_offset_s")] for n in NPC_MOVES}
    p = crossing_params(**{**late, "opp_left_offset_s": 0.0, "opp_left_speed_mps": 10.0})
    world, _ = build_intersection(p, np.random.default_rng(5))
    npc = world.npcs[left - 1]
    s_npc, _, _ = _ego_crossing(*NPC_MOVES["opp_left"])
    x, y, h = npc.path.pose(s_npc)
    world.ego.position[:] = [2.0, y + 1.0]  # in its lane, its front across the turner's arc
    world.ego.heading, world.ego.speed = -np.pi / 2, 0.0
    scenes = run(world, 20.0, accel=0.0)
    assert not any(s.crashed[[0, left]].any() for s in scenes)
    assert npc.s_m < s_npc  # it never got past the ego


def test_a_crashed_ego_stops_instead_of_rolling_through_what_it_hit():
    p = highway_params(lead_gap_m=25.0, lead_brake_time_s=3.0, lead_brake_decel_mps2=6.5,
                       lead_brake_duration_s=5.0)
    world, _ = build_highway(p, np.random.default_rng(0))
    scenes = run(world, 12.0, accel=0.0)  # an ego that never brakes runs into the lead
    k = next(i for i, s in enumerate(scenes) if s.ego_collision)
    v_hit = scenes[k].speed_mps[0]
    after = [s.x_m[0] for s in scenes[k:]]
    assert scenes[-1].speed_mps[0] == 0.0
    from evoeye.sim.npc import CRASH_DECEL_MPS2
    assert after[-1] - after[0] <= v_hit**2 / (2.0 * CRASH_DECEL_MPS2) + v_hit * DT + 1e-6
