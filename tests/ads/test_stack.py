"""The whole stack: determinism, finiteness and competent closed-loop behaviour."""

import math

import numpy as np
from conftest import DT_S, BicycleWorld, crossing_road, straight_road

from evoeye.ads import ADS, ADSConfig
from evoeye.ads.messages import PLANNING_DECISIONS

HIGHWAY_NPCS = [(45, 0, 0, 18), (25, 4, 0, 21), (12, -4, 0, 19), (-18, 4, 0, 22),
                (60, -4, 0, 20), (30, 4.0, -math.atan2(1.0, 20.0), 20.02)]


def run(road, ego, npcs, cruise, seconds, seed=0):
    world = BicycleWorld(ego=list(ego), npcs=[list(n) for n in npcs])
    ads = ADS(road, np.random.default_rng(seed), ADSConfig.cautious().with_cruise_speed(cruise))
    frames, overlap = [], False
    for _ in range(round(seconds / DT_S)):
        m = ads.step(world.scene())
        frames.append(m)
        overlap |= world.overlaps()
        world.step(m.control.accel_cmd_mps2, m.control.steering_rad)
    return frames, world, overlap


def same(a, b) -> bool:
    """Bit-identical messages (arrays compared byte for byte)."""
    for name in ("localization", "obstacles", "predictions", "plan", "control"):
        da, db = getattr(a, name).to_dict(), getattr(b, name).to_dict()
        for key in da:
            va, vb = da[key], db[key]
            if isinstance(va, np.ndarray):
                if va.shape != vb.shape or va.tobytes() != vb.tobytes():
                    return False
            elif va != vb:
                return False
    return True


def test_same_seed_gives_identical_messages_and_another_seed_does_not():
    first, _, _ = run(straight_road(), (0, 0, 0, 20), HIGHWAY_NPCS, 20.0, 3.0, seed=11)
    again, _, _ = run(straight_road(), (0, 0, 0, 20), HIGHWAY_NPCS, 20.0, 3.0, seed=11)
    other, _, _ = run(straight_road(), (0, 0, 0, 20), HIGHWAY_NPCS, 20.0, 3.0, seed=12)
    assert all(same(a, b) for a, b in zip(first, again, strict=True))
    assert not all(same(a, b) for a, b in zip(first, other, strict=True))


def test_all_outputs_finite_and_well_formed():
    frames, _, _ = run(straight_road(), (0, 0, 0, 20), HIGHWAY_NPCS, 20.0, 6.0, seed=3)
    assert all(m.all_finite() for m in frames)
    for m in frames:
        p = m.predictions
        rows = len(p.track_id)
        assert set(p.track_id.tolist()) == set(m.obstacles.track_id.tolist())
        assert p.x_m.shape == (rows, 30) and len(p.model) == rows and p.mode_prob.shape == (rows,)
        per_track = np.bincount(np.unique(p.track_id, return_inverse=True)[1], p.mode_prob)
        assert ((per_track > 0.0) & (per_track <= 1.0 + 1e-9)).all()
        assert m.plan.decision in PLANNING_DECISIONS
        assert 0.0 <= m.control.throttle <= 1.0 and 0.0 <= m.control.brake <= 1.0
        assert -8.0 <= m.control.accel_cmd_mps2 <= 3.0 and abs(m.control.steering_rad) <= 0.5
        assert ((m.obstacles.confidence >= 0.0) & (m.obstacles.confidence <= 1.0)).all()
    assert {m.plan.decision for m in frames} >= {"follow"}  # the cut-in / lead car was followed


def test_stops_behind_a_stopped_car_without_touching_it():
    frames, world, overlap = run(straight_road(), (0, 0, 0, 20), [(120, 0, 0, 0)], 20.0, 15.0)
    assert not overlap
    assert world.ego[3] < 0.2 and 5.0 < world.gap_m() < 15.0
    assert frames[-1].plan.leader_track_id >= 1


def test_waits_for_a_crossing_car_then_goes():
    north = math.pi / 2
    frames, world, overlap = run(crossing_road(), (0, -40, north, 9), [(-40, 0, 0, 9)], 9.0, 12.0)
    assert not overlap
    assert "yield" in {m.plan.decision for m in frames}
    assert world.ego[1] > 20.0  # and it went on afterwards


def test_cruise_speed_is_set_per_run():
    config = ADSConfig.cautious().with_cruise_speed(12.5)
    assert config.cruise_speed_mps == 12.5 and ADSConfig().cruise_speed_mps != 12.5
    frames, world, _ = run(straight_road(), (0, 0, 0, 12.5), [], 12.5, 2.0)
    assert abs(world.ego[3] - 12.5) < 0.2 and frames[-1].plan.target_speed_mps == 12.5


def test_a_non_finite_value_in_any_message_is_caught_and_field_values_follow_field_names():
    frames, _, _ = run(straight_road(), (0, 0, 0, 20), HIGHWAY_NPCS, 20.0, 1.0, seed=3)
    m = frames[-1]
    assert m.all_finite() and len(m.obstacles.x_m)
    for msg in (m.localization, m.obstacles, m.predictions, m.plan, m.control):
        assert msg.field_values() == tuple(getattr(msg, n) for n in msg.field_names())
    m.obstacles.vx_mps[-1] = np.nan  # an array field
    assert not m.all_finite()
    m.obstacles.vx_mps[-1] = 0.0
    m.control.steering_rad = math.inf  # a scalar field
    assert not m.all_finite()
    m.control.steering_rad = 0.0
    m.predictions.y_m[0, -1] = -math.inf  # a (n, K) field
    assert not m.all_finite()
