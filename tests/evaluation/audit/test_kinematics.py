"""Kinematic bounds on hand-built NPC paths: lane changes, braking, lanes that are not along x."""

from __future__ import annotations

import numpy as np
import pytest
from audit_scenes import RATE_HZ, ActorPath, build_tracks, lane_change_vy, straight_lanes

from evoeye.evaluation.audit.kinematics import check_kinematics, road_lateral_speed

N = 100  # frames (5 s)


def _cut_in(a_lat_mps2: float) -> list[ActorPath]:
    vy = lane_change_vy(a_lat_mps2, N)
    npc = ActorPath.from_velocity(4, 30.0, 0.0, np.full(N, 25.0), vy)
    return [ActorPath.parked(0, N, -50.0, 0.0), npc]


def test_a_sharp_lane_change_is_caught_and_a_gentle_one_is_not() -> None:
    sharp = check_kinematics(build_tracks(_cut_in(6.0)), straight_lanes(), RATE_HZ)
    assert set(sharp.exceeded) == {"a_lat", "lat_speed"}
    assert sharp.a_lat.actor_id == 4 and sharp.a_lat.value == pytest.approx(6.0, abs=0.3)
    assert sharp.lat_speed.value == pytest.approx(np.sqrt(3.5 * 6.0), abs=0.2)
    assert 1.0 <= sharp.a_lat.t_s <= 2.5  # during the manoeuvre (it starts at 1 s)
    gentle = check_kinematics(build_tracks(_cut_in(2.0)), straight_lanes(), RATE_HZ)
    assert not gentle.violated
    assert gentle.a_lat.value == pytest.approx(2.0, abs=0.2)
    assert gentle.lat_speed.value == pytest.approx(np.sqrt(3.5 * 2.0), abs=0.2)


def test_only_frames_before_the_egos_first_collision_count() -> None:
    paths = _cut_in(6.0)  # the manoeuvre starts at frame 20
    assert check_kinematics(build_tracks(paths, ego_collision_frame=21), straight_lanes(),
                            RATE_HZ).violated is False
    assert check_kinematics(build_tracks(paths, ego_collision_frame=40), straight_lanes(),
                            RATE_HZ).violated


def test_the_ego_itself_is_never_checked() -> None:
    paths = _cut_in(6.0)
    paths[0].actor_id, paths[1].actor_id = paths[1].actor_id, 0  # the swerving car is the ego
    result = check_kinematics(build_tracks(paths), straight_lanes(), RATE_HZ)
    assert not result.violated and result.a_lat.actor_id == 4


@pytest.mark.parametrize(("decel_mps2", "violated"), [(10.0, True), (8.0, False)])
def test_hard_braking_against_the_longitudinal_bound(decel_mps2: float, violated: bool) -> None:
    t = np.arange(N) / RATE_HZ
    vx = np.maximum(25.0 - decel_mps2 * np.clip(t - 1.0, 0.0, None), 0.5)
    paths = [ActorPath.parked(0, N, -50.0, 0.0),
             ActorPath.from_velocity(2, 30.0, 0.0, vx, np.zeros(N))]
    result = check_kinematics(build_tracks(paths), straight_lanes(), RATE_HZ)
    assert result.a_lon.value == pytest.approx(decel_mps2, abs=0.1)
    assert ("a_lon" in result.exceeded) is violated


def test_lateral_speed_is_taken_against_the_lane_not_the_x_axis() -> None:
    # a car driving straight along a diagonal lane at 20 m/s has no lateral speed
    s = np.linspace(0.0, 400.0, 50)
    diagonal = (np.stack([s, s], axis=1) / np.sqrt(2.0),)
    v = np.full(N, 20.0 / np.sqrt(2.0))
    paths = [ActorPath.parked(0, N, -50.0, 0.0), ActorPath.from_velocity(1, 10.0, 10.0, v, v)]
    lat = road_lateral_speed(build_tracks(paths), diagonal)
    assert np.nanmax(lat[:, 1]) < 1e-6
    # the same motion from a lane running along x is 14 m/s across it (while within reach)
    paths[1] = ActorPath.from_velocity(1, 10.0, 0.0, v, v)
    lat_x = road_lateral_speed(build_tracks(paths), straight_lanes(1))
    assert np.nanmax(lat_x[:, 1]) == pytest.approx(20.0 / np.sqrt(2.0), abs=0.01)


def test_a_crossing_lane_nearby_is_not_the_lane_a_car_follows() -> None:
    # a car on a lane along +x, right by a crossing lane along +y: only its own lane matches
    x = np.linspace(-100.0, 100.0, 50)
    lanes = (np.stack([x, np.zeros_like(x)], axis=1), np.stack([np.zeros_like(x) + 0.5, x], axis=1))
    vx = np.full(N, 15.0)
    paths = [ActorPath.parked(0, N, -80.0, 0.0),
             ActorPath.from_velocity(1, -20.0, 0.0, vx, np.zeros(N))]
    assert np.nanmax(road_lateral_speed(build_tracks(paths), lanes)[:, 1]) < 1e-6


def test_a_car_off_the_map_has_no_lateral_speed() -> None:
    paths = [ActorPath.parked(0, N, -50.0, 0.0),
             ActorPath.from_velocity(1, 0.0, 200.0, np.full(N, 20.0), np.zeros(N))]
    lat = road_lateral_speed(build_tracks(paths), straight_lanes())
    assert np.isnan(lat[:, 1]).all() and not np.isnan(lat[:, 0]).all()
