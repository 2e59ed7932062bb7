"""occluded-crossing's world: parked cars that hide, pedestrians timed to the ego, a kerb wait."""

import numpy as np
import pytest

from evoeye.ads.sensing import line_of_sight_blocked
from evoeye.scenarios import get_scenario
from evoeye.sim import crossing
from evoeye.sim.crossing import CROSSING_GAP_M, build_crossing, parked_cars

SPACE = get_scenario("occluded-crossing")
DT = 0.05


def params(**changes):
    p = SPACE.as_dict(SPACE.sample(np.random.default_rng(0)))
    p.update(changes)
    return SPACE.as_dict(SPACE.validate(SPACE.from_dict(p)))


def drive_blind(world, seconds):
    """Step the world with the ego holding its speed; the scenes, one per step."""
    scenes = []
    for _ in range(int(round(seconds / DT))):
        scenes.append(world.scene())
        world.step(0.0, 0.0, DT)
    return scenes


def test_parked_cars_leave_a_gap_at_each_crossing_and_stay_off_the_ego_lane():
    xs = [120.0, 150.0, 200.0]
    boxes = parked_cars(xs, 1.0, np.random.default_rng(0))
    assert len(boxes) > 40
    assert boxes[:, 1].min() > 2.0  # the ego's lane ends at y = 2 m
    for x in xs:
        overlap = (boxes[:, 0] < x + 0.5 * CROSSING_GAP_M - 1e-9) & (
            boxes[:, 2] > x - 0.5 * CROSSING_GAP_M + 1e-9)
        assert not overlap.any()
        assert np.isclose(boxes[:, 2], x - 0.5 * CROSSING_GAP_M).any()  # a car right upstream
    order = np.argsort(boxes[:, 0])
    assert (boxes[order][1:, 0] - boxes[order][:-1, 2] >= 1.0 - 1e-9).all()  # no overlaps


def test_a_pedestrian_in_the_gap_is_hidden_from_upstream_and_seen_once_out():
    x = 150.0
    boxes = parked_cars([x], 1.0, np.random.default_rng(0))
    ego = (x - 30.0, 0.0)
    in_gap, stepped_out = np.array([x, x]), np.array([4.0, 2.6])
    hidden = line_of_sight_blocked(*ego, in_gap, stepped_out, boxes)
    assert hidden.tolist() == [True, False]


def test_pedestrians_are_small_slow_and_exist_from_the_start():
    world, cruise = build_crossing(params(), np.random.default_rng(1))
    scene = world.scene()
    assert scene.n == 4 and cruise == pytest.approx(params()["ego_speed_mps"])
    np.testing.assert_allclose(scene.length_m[1:], crossing.PED_LENGTH_M)
    np.testing.assert_allclose(scene.width_m[1:], crossing.PED_WIDTH_M)
    speeds = np.array([s.speed_mps[1:] for s in drive_blind(world, 5.0)])
    assert speeds.max() <= SPACE.parameters[SPACE.index("hidden_ped_speed_mps")].high + 1e-9


@pytest.mark.parametrize("offset_s", [-2.5, -1.0])
def test_the_hidden_pedestrian_reaches_the_ego_lane_when_its_offset_says(offset_s):
    p = params(ego_speed_mps=10.0, hidden_ped_ahead_m=60.0, hidden_ped_speed_mps=1.5,
               hidden_ped_offset_s=offset_s, kerb_ped_ahead_m=180.0, turn_ped_ahead_m=180.0)
    world, _ = build_crossing(p, np.random.default_rng(2))
    y = np.array([s.y_m[1] for s in drive_blind(world, 8.0)])
    t_cross = DT * int(np.argmax(y <= 0.0))
    assert t_cross == pytest.approx(60.0 / 10.0 + offset_s, abs=0.5)


def test_the_kerb_pedestrian_waits_until_the_ego_is_within_its_go_time():
    p = params(ego_speed_mps=10.0, kerb_ped_ahead_m=100.0, kerb_ped_offset_s=-2.5,
               kerb_ped_go_s=4.0, hidden_ped_ahead_m=180.0, turn_ped_ahead_m=180.0)
    world, _ = build_crossing(p, np.random.default_rng(3))
    scenes = drive_blind(world, 9.0)
    y = np.array([s.y_m[2] for s in scenes])
    t = DT * np.arange(len(scenes))
    before = t < 10.0 - 4.0  # the ego is 100 m out at 10 m/s: within 4 s from t = 6 s
    assert y[before].max() <= crossing.KERB_WAIT_Y_M + 0.05  # it waited at the kerb …
    assert y[~before].max() > crossing.KERB_WAIT_Y_M + 1.0  # … and then stepped off
