"""The sensor model: range, field of view, occlusion, misses and noise."""

import math
from dataclasses import replace

import numpy as np
from conftest import ideal_sensor, make_scene

from evoeye.ads import ADSConfig
from evoeye.ads.clutter import CLUTTER_ID, GHOST_ID
from evoeye.ads.config import SensorConfig
from evoeye.ads.detections import (
    DET_FIELDS,
    DET_LENGTH,
    DET_RANGE,
    DET_VAR_POS,
    DET_VX,
    DET_VY,
    DET_WIDTH,
    DET_X,
    DET_Y,
    VAR_FLOOR,
)
from evoeye.ads.sensing import SensorModel, occluded_fraction


def detected(scene, config=None, seed=0):
    return set(SensorModel(config or ideal_sensor(), np.random.default_rng(seed)).detect(
        scene).actor_id.tolist())


def test_a_car_hidden_behind_a_nearer_one_is_not_reported():
    scene = make_scene(0.0, [(0, 0, 0, 20), (20, 0, 0, 20), (45, 0.2, 0, 20)])
    assert detected(scene) == {1}


def test_a_car_only_partly_behind_a_nearer_one_is_reported():
    scene = make_scene(0.0, [(0, 0, 0, 20), (20, 0, 0, 20), (45, 3.0, 0, 20)])
    assert detected(scene) == {1, 2}


def test_lidar_sees_all_around_and_the_radar_far_ahead():
    scene = make_scene(0.0, [
        (0, 0, 0, 20),
        (60, 10, 0, 20),  # ahead, within the lidar's range: seen
        (150, 5, 0, 20),  # 2° off the nose at 150 m: the radar sees it
        (150, 40, 0, 20),  # 15° off the nose, beyond the lidar: not seen
        (-60, 4, 0, 20),  # behind, within the lidar's range: seen
        (-90, 0, 0, 20),  # behind, beyond it: not seen
        (10, 80, math.pi / 2, 5),  # 83° to the left, 81 m: not seen
    ])
    assert detected(scene) == {1, 2, 4}


def test_occluded_fraction_counts_only_nearer_actors():
    r = np.array([10.0, 20.0])
    b = np.array([0.0, 0.0])
    a = np.array([0.1, 0.05])
    occ = occluded_fraction(r, b, a)
    assert occ[0] == 0.0 and occ[1] == 1.0
    half = occluded_fraction(r, np.array([0.0, 0.1]), np.array([0.05, 0.05]))  # edges touch
    assert half[1] == 0.0


LIDAR_ONLY = dict(radar_detect_prob_near=0.0, radar_detect_prob_far=0.0,
                  clutter_rate_per_frame=0.0, ghost_prob=0.0)


def test_misses_grow_with_range():
    config = replace(SensorConfig(), lidar_detect_prob_near=0.98, lidar_detect_prob_far=0.5,
                     **LIDAR_ONLY)
    rng = np.random.default_rng(3)
    near = make_scene(0.0, [(0, 0, 0, 0), (10, 0, 0, 0)])
    far = make_scene(0.0, [(0, 0, 0, 0), (60, 30, 0, 0)])  # 67 m: p ≈ 0.60
    sensor = SensorModel(config, rng)
    hits_near = sum(len(sensor.detect(near).actor_id) for _ in range(400))
    hits_far = sum(len(sensor.detect(far).actor_id) for _ in range(400))
    assert hits_near > 370 and 190 < hits_far < 290


def test_noise_grows_with_range_and_variances_are_reported():
    rng = np.random.default_rng(4)
    sensor_cfg = replace(ADSConfig.cautious().sensor, lidar_detect_prob_near=1.0,
                         lidar_detect_prob_far=1.0, lidar_depth_seen_frac=1.0, **LIDAR_ONLY)
    sensor = SensorModel(sensor_cfg, rng)
    scene = make_scene(0.0, [(0, 0, 0, 0), (10, -8, 0, 12), (70, 8, 0, 12)])
    errs = np.array([sensor.detect(scene).z[DET_X] for _ in range(300)]) - [10.0, 70.0]
    std = errs.std(axis=0)
    assert std[1] > 2.0 * std[0]
    z = sensor.detect(scene).z
    expected = sensor_cfg.pos_sigma_m + sensor_cfg.pos_sigma_per_m * z[DET_RANGE]
    assert np.allclose(z[DET_VAR_POS], expected**2 + VAR_FLOOR)
    assert np.allclose(z[DET_VX], 12.0, atol=2.0)


def test_empty_scene_has_no_detections_without_clutter():
    quiet = replace(ADSConfig.cautious().sensor, clutter_rate_per_frame=0.0)
    d = SensorModel(quiet, np.random.default_rng(0)).detect(make_scene(0.0, [(0, 0, 0, 1)]))
    assert d.z.shape == (DET_FIELDS, 0) and d.actor_id.shape == (0,)


def test_clutter_count_is_poisson_and_capped():
    config = replace(SensorConfig(), clutter_rate_per_frame=1.5, clutter_max_per_frame=4)
    sensor = SensorModel(config, np.random.default_rng(5))
    scene = make_scene(0.0, [(0, 0, 0, 10)])
    counts = np.array([len(sensor.detect(scene).actor_id) for _ in range(2000)])
    assert abs(counts.mean() - 1.5) < 0.15 and counts.max() == 4
    d = sensor.detect(scene)
    assert (d.actor_id == CLUTTER_ID).all()
    assert (d.z[DET_RANGE] <= config.lidar_range_m).all()


def test_a_radar_ghost_mirrors_a_far_car_at_the_guard_rail():
    config = ideal_sensor(ghost_prob=1.0, ghost_rail_offset_m=8.0)
    d = SensorModel(config, np.random.default_rng(0)).detect(
        make_scene(0.0, [(0, 0, 0, 20), (60, 4, 0.05, 20)]))
    ghost = d.actor_id == GHOST_ID
    assert np.count_nonzero(ghost) == 1
    assert np.isclose(d.z[DET_Y, ghost][0], 12.0) and np.isclose(d.z[DET_X, ghost][0], 60.0)
    near = SensorModel(config, np.random.default_rng(0)).detect(
        make_scene(0.0, [(0, 0, 0, 20), (20, 4, 0, 20)]))
    assert GHOST_ID not in near.actor_id  # too near for multipath


def test_close_cars_merge_into_one_segment():
    side_by_side = make_scene(0.0, [(0, 0, 0, 0), (30, 5.0, 0, 0), (30, 7.3, 0, 0)])
    d = SensorModel(ideal_sensor(radar_detect_prob_near=0.0, radar_detect_prob_far=0.0),
                    np.random.default_rng(0)).detect(side_by_side)
    assert d.actor_id.tolist() == [1]
    assert np.isclose(d.z[DET_WIDTH][0], 4.3) and np.isclose(d.z[DET_Y][0], 6.15)
    apart = make_scene(0.0, [(0, 0, 0, 0), (30, 5.0, 0, 0), (30, 8.0, 0, 0)])
    assert detected(apart) == {1, 2}


def test_lidar_boxes_seen_end_on_are_short_and_shifted_towards_the_sensor():
    config = replace(ideal_sensor(), lidar_depth_seen_frac=0.5, radar_detect_prob_near=0.0,
                     radar_detect_prob_far=0.0)
    d = SensorModel(config, np.random.default_rng(0)).detect(
        make_scene(0.0, [(0, 0, 0, 0), (30, 0, 0, 0)]))
    assert np.isclose(d.z[DET_LENGTH][0], 2.5) and np.isclose(d.z[DET_WIDTH][0], 2.0)
    assert np.isclose(d.z[DET_X][0], 30.0 - 1.25)  # the rear is where it is


def test_radar_only_targets_have_poor_azimuth_and_no_tangential_velocity():
    config = replace(SensorConfig(), clutter_rate_per_frame=0.0, ghost_prob=0.0,
                     radar_detect_prob_near=1.0, radar_detect_prob_far=1.0)
    sensor = SensorModel(config, np.random.default_rng(6))
    scene = make_scene(0.0, [(0, 0, 0, 0), (150, 0, math.pi / 2, 10.0)])  # crossing, far ahead
    z = np.concatenate([sensor.detect(scene).z for _ in range(300)], axis=1)
    assert z[DET_Y].std() > 2.0 * z[DET_X].std()  # lateral worse than range
    assert np.abs(z[DET_VY]).max() < 0.5  # the crossing speed is invisible to it
