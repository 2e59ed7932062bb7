"""NPC drivers' rules in isolation: giving way to the ego, settling crossings, a blocked turn."""

import math

import numpy as np
import pytest

from evoeye.sim.npc import CUT_IN_EGO_DECEL_MPS2, CUT_IN_EGO_REACTION_S, cut_in_gap_m
from evoeye.sim.path import Path
from evoeye.sim.traffic import (
    CLEAR_MARGIN_S,
    COMMIT_DECEL_MPS2,
    PASSED_M,
    Conflict,
    YieldToEgo,
    may_curve,
    path_block,
)


def yield_rule() -> YieldToEgo:
    # the NPC's crossing with the ego's route is at s = 100 on its path, its stop point at 94;
    # the crossing is at s = 300 on the ego's route
    return YieldToEgo(i=1, s_i=100.0, s_ego=300.0, stop_i=94.0, gap_s=2.0)


def test_a_turning_npc_that_saw_a_gap_still_waits_if_the_ego_turns_out_to_arrive_sooner():
    rule = yield_rule()
    # 50 m out at 8 m/s (6.25 s); the ego 150 m out at 10 m/s (15 s): the gap is long, it goes …
    assert rule.wait_gap(50.0, 8.0, 150.0, 10.0) is None and not rule.going
    # … 20 m out at 8 m/s the ego, having sped up, is 2 s from the crossing: it stops after all
    assert rule.wait_gap(80.0, 8.0, 270.0, 15.0) == pytest.approx(14.0)


def test_a_turning_npc_is_committed_once_it_could_no_longer_stop_comfortably():
    rule = yield_rule()
    v = 8.0  # 8 m/s needs 10.7 m at COMMIT_DECEL_MPS2: from 5 m before its stop point it goes
    to_stop = 0.9 * v * v / (2.0 * COMMIT_DECEL_MPS2)
    assert rule.wait_gap(94.0 - to_stop, v, 150.0, 10.0) is None and rule.going
    assert rule.wait_gap(94.0 - to_stop + 1.0, v, 295.0, 10.0) is None  # the ego came: too late


def test_a_turning_npc_waits_for_an_ego_that_comes_within_the_accepted_gap():
    rule = yield_rule()
    # 10 m out at 5 m/s (2 s); the ego 25 m out at 10 m/s (2.5 s): less than 2 s after it
    assert rule.wait_gap(90.0, 5.0, 275.0, 10.0) == pytest.approx(4.0)
    assert not rule.going


def crossing() -> Conflict:
    # NPC rows 1 and 2 cross at s = 100 on both paths; each stops 6 m before
    return Conflict(i=1, j=2, s_i=100.0, s_j=100.0, stop_i=94.0, stop_j=94.0)


def test_the_npc_that_would_arrive_second_waits_only_if_its_timing_calls_for_it():
    c = crossing()
    s, v = {1: 60.0, 2: 50.0}, {1: 10.0, 2: 10.0}
    # row 1 is 40 m (4 s) out, row 2 50 m (5 s): row 1 goes first and clears 4.6 s from now;
    # row 2 reaches its stop point in 4.4 s — too soon: it waits
    assert c.wait_gap(s, v) == (2, pytest.approx(44.0))
    assert c.first == 1
    # with row 2 slower it would only get there after row 1 has cleared: no need to slow
    slow = {1: 10.0, 2: 44.0 / (4.6 + CLEAR_MARGIN_S + 0.5)}
    assert c.wait_gap(s, slow) is None


def test_turning_traffic_gives_way_to_straight_traffic_whoever_would_arrive_first():
    c = Conflict(i=1, j=2, s_i=100.0, s_j=100.0, stop_i=94.0, stop_j=94.0, first=2)
    s, v = {1: 80.0, 2: 50.0}, {1: 10.0, 2: 10.0}  # row 1 (turning) would be there first
    assert c.wait_gap(s, v) == (1, pytest.approx(14.0))
    s[2] = 100.0 + PASSED_M + 0.1  # the straight car is through
    assert c.wait_gap(s, v) is None


def test_the_accepted_cut_in_gap_leaves_the_ego_a_hard_but_ordinary_stop():
    for closing in (0.0, 3.0, 10.0, 15.0):
        gap = cut_in_gap_m(closing)
        # braking at the accepted rate after the reaction time, the ego just keeps the gap
        stop = closing * CUT_IN_EGO_REACTION_S + closing**2 / (2.0 * CUT_IN_EGO_DECEL_MPS2)
        assert gap == pytest.approx(stop)
    assert cut_in_gap_m(-5.0) == 0.0  # a cut-in pulling away needs no gap
    assert cut_in_gap_m(10.0) / 10.0 > cut_in_gap_m(5.0) / 5.0  # faster closing: longer TTC


def arc_path() -> Path:
    """A left turn: 30 m straight east, a quarter circle of radius 12 m, then north."""
    a = np.linspace(-math.pi / 2, 0.0, 40)
    straight = np.stack((np.linspace(-30.0, 0.0, 31), np.full(31, -12.0)), axis=1)
    arc = np.stack((12.0 * np.cos(a), 12.0 * np.sin(a)), axis=1)
    north = np.stack((np.full(30, 12.0), np.linspace(0.0, 30.0, 30)), axis=1)
    return Path(np.concatenate((straight, arc[1:], north[1:])))


def blocking(path, s_m, others):
    """path_block for an NPC (5 × 2 m) at arc length s_m and cars (x, y, heading) `others`."""
    rows = [(0.0, 0.0, 0.0)] + list(others)  # row 0 stands for the NPC itself
    x, y, h = (np.array(c, dtype=float) for c in zip(*rows, strict=True))
    n = len(rows)
    return path_block(path, s_m, 2.5, 1.0, x, y, h, np.full(n, 2.5), np.full(n, 1.0), 0)


def test_a_car_standing_in_a_turn_blocks_it_though_it_is_not_straight_ahead():
    p = arc_path()
    s0 = 20.0  # 10 m before the bend, heading east
    # a car across the arc, where it heads north-east: far off the NPC's straight-ahead line
    k = p.index(30.0 + 12.0 * math.pi / 4)
    gap = blocking(p, s0, [(p.x[k], p.y[k], 3.0 * math.pi / 4)])
    along = 30.0 + 12.0 * math.pi / 4 - s0
    assert along - 2.5 - 2.6 < gap < along - 2.5  # its front to the box's nearest edge
    assert blocking(p, s0, [(p.x[k] + 6.0, p.y[k] - 6.0, 3.0 * math.pi / 4)]) == math.inf
    # a car driving its way along the arc is a leader, not a blocker
    assert blocking(p, s0, [(p.x[k], p.y[k], p.h[k])]) == math.inf


def test_a_straight_path_is_left_to_the_straight_corridor():
    p = Path(np.stack((np.linspace(0.0, 200.0, 201), np.zeros(201)), axis=1))
    assert blocking(p, 20.0, [(35.0, 0.0, math.pi / 2)]) == math.inf
    assert not may_curve(p)  # so the world never asks: nothing can block it along an arc
    assert may_curve(arc_path())
    gentle = Path(np.stack((np.linspace(0.0, 200.0, 201), np.linspace(0.0, 10.0, 201)), axis=1))
    assert not may_curve(gentle)  # a slanted straight line turns nowhere either


def test_only_the_west_approach_lane_that_ends_at_the_box_gives_way() -> None:
    from evoeye.sim.intersection import _network

    _, road = _network()
    giving = [ln for ln in road.lanes if ln.yields_to_route]
    assert len(giving) == 1  # the lane that ends at the stop line, not the one before it
    end = giving[0].points[-1]
    route = road.route.points
    assert np.min(np.hypot(*(route - end).T)) < 15.0  # its end is at the ego's route
    assert end[0] < 0.0  # on the west side


def test_a_turning_npc_is_settled_for_good_once_it_went_or_passed_its_stop_point():
    rule = yield_rule()
    assert not rule.settled(90.0)  # before its stop point, undecided: it may still wait
    assert rule.settled(94.5)  # past its stop point: whatever the ego does
    assert rule.wait_gap(94.5, 0.5, 299.0, 0.1) is None
    # a long gap 50 m out: it may go, but could still stop, so the ego is judged again …
    assert rule.wait_gap(50.0, 8.0, 150.0, 10.0) is None and not rule.settled(50.0)
    # … 1 m before its stop point it is committed, and stays so whenever the ego comes
    assert rule.wait_gap(93.0, 8.0, 150.0, 10.0) is None and rule.going
    assert rule.settled(93.0) and rule.wait_gap(93.0, 8.0, 299.0, 10.0) is None
