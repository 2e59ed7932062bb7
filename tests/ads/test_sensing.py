"""The sensor model: range, field of view, occlusion, misses and noise."""

import math
from dataclasses import replace

import numpy as np
from conftest import ideal_sensor, make_scene

from evoeye.ads import ADSConfig
from evoeye.ads.config import SensorConfig
from evoeye.ads.sensing import DET_RANGE, DET_VX, DET_X, SensorModel, occluded_fraction


def detected(scene, config=None, seed=0):
    return set(SensorModel(config or ideal_sensor(), np.random.default_rng(seed)).detect(
        scene).actor_id.tolist())


def test_a_car_hidden_behind_a_nearer_one_is_not_reported():
    scene = make_scene(0.0, [(0, 0, 0, 20), (20, 0, 0, 20), (45, 0.2, 0, 20)])
    assert detected(scene) == {1}


def test_a_car_only_partly_behind_a_nearer_one_is_reported():
    scene = make_scene(0.0, [(0, 0, 0, 20), (20, 0, 0, 20), (45, 3.0, 0, 20)])
    assert detected(scene) == {1, 2}


def test_range_and_field_of_view_limits():
    scene = make_scene(0.0, [
        (0, 0, 0, 20),
        (90, 10, 0, 20),  # ahead, in the front sensor's range: seen
        (120, 0, 0, 20),  # ahead beyond the front range: not seen
        (-20, 4, 0, 20),  # behind, within the surround range: seen
        (-50, 0, 0, 20),  # behind, beyond the surround range: not seen
        (10, 40, math.pi / 2, 5),  # 76° to the left, 41 m: outside the front FOV, beyond surround
    ])
    assert detected(scene) == {1, 3}


def test_occluded_fraction_counts_only_nearer_actors():
    r = np.array([10.0, 20.0])
    b = np.array([0.0, 0.0])
    a = np.array([0.1, 0.05])
    occ = occluded_fraction(r, b, a)
    assert occ[0] == 0.0 and occ[1] == 1.0
    half = occluded_fraction(r, np.array([0.0, 0.1]), np.array([0.05, 0.05]))  # edges touch
    assert half[1] == 0.0


def test_misses_grow_with_range():
    config = SensorConfig(detect_prob_near=0.98, detect_prob_far=0.5)
    rng = np.random.default_rng(3)
    near = make_scene(0.0, [(0, 0, 0, 0), (10, 0, 0, 0)])
    far = make_scene(0.0, [(0, 0, 0, 0), (95, 0, 0, 0)])
    sensor = SensorModel(config, rng)
    hits_near = sum(len(sensor.detect(near).actor_id) for _ in range(400))
    hits_far = sum(len(sensor.detect(far).actor_id) for _ in range(400))
    assert hits_near > 370 and 150 < hits_far < 280


def test_noise_grows_with_range_and_variances_are_reported():
    rng = np.random.default_rng(4)
    sensor_cfg = replace(ADSConfig.cautious().sensor, detect_prob_near=1.0, detect_prob_far=1.0)
    sensor = SensorModel(sensor_cfg, rng)
    scene = make_scene(0.0, [(0, 0, 0, 0), (10, -8, 0, 12), (80, 8, 0, 12)])
    errs = np.array([sensor.detect(scene).z[DET_X] for _ in range(300)]) - [10.0, 80.0]
    std = errs.std(axis=0)
    assert std[1] > 2.5 * std[0]
    z = sensor.detect(scene).z
    expected = sensor_cfg.pos_sigma_m + sensor_cfg.pos_sigma_per_m * z[DET_RANGE]
    assert np.allclose(z[8], expected**2 + 1e-4)
    assert np.allclose(z[DET_VX], 12.0, atol=2.0)


def test_empty_scene_has_no_detections():
    sensor = SensorModel(ADSConfig.cautious().sensor, np.random.default_rng(0))
    d = sensor.detect(make_scene(0.0, [(0, 0, 0, 1)]))
    assert d.z.shape == (10, 0) and d.actor_id.shape == (0,)
