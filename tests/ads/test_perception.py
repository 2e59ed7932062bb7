"""Perception end to end: latency, track management, the Kalman filter, occlusion."""

import math
from dataclasses import replace

import numpy as np
from conftest import DT_S, ego_at, ideal_sensor, make_scene

from evoeye.ads import ADSConfig
from evoeye.ads.config import SensorConfig, TrackerConfig
from evoeye.ads.perception import TrackingPerception


def perception(sensor: SensorConfig, tracker: TrackerConfig | None = None, seed: int = 0):
    return TrackingPerception(sensor, tracker or TrackerConfig(), DT_S, np.random.default_rng(seed))


def drive(per, frames, car_at, ego=(0.0, 0.0, 0.0, 20.0)):
    """Run `frames` frames; car_at(k) gives the NPC rows at frame k. Returns the messages."""
    out = []
    for k in range(frames):
        t = k * DT_S
        ego_row = (ego[0] + ego[3] * t, ego[1], ego[2], ego[3])
        out.append(per.perceive(make_scene(t, [ego_row, *car_at(k)]), ego_at(*ego_row, t_s=t)))
    return out


def test_latency_is_compensated_by_predicting_the_tracks_forward():
    speed = 20.0
    for compensate, lag in ((True, 0.0), (False, speed * 0.1)):
        per = perception(ideal_sensor(latency_s=0.1, compensate_latency=compensate))
        msgs = drive(per, 40, lambda k: [(30.0 + speed * k * DT_S, 4.0, 0.0, speed)])
        true_x = 30.0 + speed * 39 * DT_S
        assert len(msgs[-1].track_id) == 1
        assert abs((true_x - msgs[-1].x_m[0]) - lag) < 0.05


def test_what_latency_compensation_leaves_is_the_unmodelled_acceleration():
    def err(accel, latency):
        per = perception(ideal_sensor(latency_s=latency))
        msgs = drive(per, 40, lambda k: [(30.0 + 10.0 * k * DT_S + 0.5 * accel * (k * DT_S) ** 2,
                                          4.0, 0.0, 10.0 + accel * k * DT_S)])
        t = 39 * DT_S
        return 30.0 + 10.0 * t + 0.5 * accel * t * t - msgs[-1].x_m[0]

    assert abs(err(0.0, 0.25)) < 0.05
    assert err(4.0, 0.25) > 0.1  # it lags behind an accelerating car …
    assert err(4.0, 0.25) < 0.5 * 0.25 * 14.0  # … by far less than its speed · latency
    assert err(4.0, 0.25) > err(4.0, 0.1)  # and more the longer the latency


def test_detections_are_placed_with_the_estimated_ego_pose_at_capture():
    per = perception(ideal_sensor())
    scene = make_scene(0.0, [(0.0, 0.0, 0.0, 0.0), (30.0, 4.0, 0.0, 0.0)])
    z_true = per.sensor.detect(scene, ego_at(0.0, 0.0)).z
    z_off = per.sensor.detect(scene, ego_at(1.0, 0.0, 0.02)).z
    assert np.isclose(z_off[0, 0] - z_true[0, 0], 1.0 - 4.0 * 0.02, atol=0.02)
    assert np.isclose(z_off[1, 0] - z_true[1, 0], 30.0 * 0.02, atol=0.02)


def test_nothing_is_published_before_the_latency_and_the_confirmation():
    per = perception(ideal_sensor(latency_s=0.1), TrackerConfig(confirm_hits=3))
    msgs = drive(per, 6, lambda k: [(30.0, 4.0, 0.0, 0.0)])
    counts = [len(m.track_id) for m in msgs]
    # detections of frame 0 reach the tracker at frame 2; the 3rd hit comes at frame 4
    assert counts == [0, 0, 0, 0, 1, 1]


def test_track_id_is_stable_and_a_new_one_is_issued_after_a_long_absence():
    config = TrackerConfig(max_coast_frames=10)
    sensor = replace(SensorConfig(), lidar_detect_prob_far=0.9, clutter_rate_per_frame=0.0,
                     ghost_prob=0.0)
    per = perception(sensor, config, seed=5)

    def car(k):  # visible for 40 frames, gone (far away) for 20, back again
        return [(25.0 + 20.0 * k * DT_S, 4.0, 0.0, 20.0)] if (k < 40 or k >= 60) else [
            (5000.0, 4.0, 0.0, 20.0)]

    msgs = drive(per, 80, car)
    ids_first = {int(i) for m in msgs[8:40] for i in m.track_id}
    assert len(ids_first) == 1 and all(len(m.track_id) == 1 for m in msgs[8:40])
    assert all(len(m.track_id) == 0 for m in msgs[55:62])  # coasting ended, deleted
    ids_later = {int(i) for m in msgs[70:] for i in m.track_id}
    assert len(ids_later) == 1 and ids_later.isdisjoint(ids_first)


def test_a_short_dropout_is_coasted_under_the_same_id():
    per = perception(ideal_sensor(), TrackerConfig(max_coast_frames=10))

    def car(k):
        x = 25.0 + 20.0 * k * DT_S
        return [(x, 4.0, 0.0, 20.0)] if not 20 <= k < 25 else [(5000.0, 4.0, 0.0, 20.0)]

    msgs = drive(per, 40, car)
    assert {int(i) for m in msgs[5:] for i in m.track_id} == {1}
    coasting = msgs[23]
    assert coasting.confidence[0] < msgs[19].confidence[0]  # confidence decays while coasting
    assert abs(coasting.x_m[0] - (25.0 + 20.0 * 23 * DT_S)) < 0.5  # predicted forward


def test_kalman_velocity_converges_to_the_truth():
    per = perception(replace(SensorConfig(), lidar_detect_prob_far=1.0, radar_detect_prob_far=1.0,
                             clutter_rate_per_frame=0.0, ghost_prob=0.0), seed=2)
    vx, vy = 15.0, -1.0
    heading, speed = np.arctan2(vy, vx), np.hypot(vx, vy)
    msgs = drive(per, 60, lambda k: [(40.0 + vx * k * DT_S, 4.0 + vy * k * DT_S, heading, speed)],
                 ego=(0.0, 0.0, 0.0, 0.0))
    est = np.array([[m.vx_mps[0], m.vy_mps[0]] for m in msgs[30:]])
    assert np.allclose(est.mean(axis=0), [vx, vy], atol=0.3)
    assert (np.abs(est - [vx, vy]) < 1.5).all()


def test_confidence_is_in_unit_interval_and_grows_with_hits():
    per = perception(ideal_sensor())
    msgs = drive(per, 30, lambda k: [(30.0 + 20.0 * k * DT_S, 4.0, 0.0, 20.0)])
    conf = np.array([m.confidence[0] for m in msgs[3:]])
    assert ((conf > 0.0) & (conf <= 1.0)).all()
    assert conf[-1] > conf[0]


def test_an_occluded_car_is_never_published():
    per = perception(ADSConfig.cautious().sensor)  # default: noise and misses
    msgs = drive(per, 40, lambda k: [(20.0 + 20.0 * k * DT_S, 0.0, 0.0, 20.0),
                                     (45.0 + 20.0 * k * DT_S, 0.1, 0.0, 20.0)])
    assert all(len(m.track_id) <= 1 for m in msgs)
    assert all(abs(m.x_m[0] - (20.0 + 20.0 * k * DT_S)) < 5.0 for k, m in enumerate(msgs)
               if len(m.track_id))


def test_clutter_is_rejected_by_confirmation_but_ghosts_are_tracked():
    quiet = replace(SensorConfig(), ghost_prob=0.0, clutter_rate_per_frame=2.0)
    per = perception(quiet, seed=3)
    msgs = drive(per, 200, lambda k: [(30.0 + 20.0 * k * DT_S, 0.0, 0.0, 20.0)])
    assert max(len(m.track_id) for m in msgs[20:]) <= 2  # at most a rare confirmed burst
    assert np.mean([len(m.track_id) for m in msgs[20:]]) < 1.1
    ghostly = replace(SensorConfig(), ghost_prob=0.7, clutter_rate_per_frame=0.0)
    per = perception(ghostly, seed=3)  # a car 60 m ahead one lane left: its mirror at y = 12
    msgs = drive(per, 100, lambda k: [(60.0 + 20.0 * k * DT_S, 4.0, 0.0, 20.0)])
    ys = np.concatenate([m.y_m for m in msgs[50:]])
    assert np.count_nonzero(np.abs(ys - 12.0) < 2.0) > 25  # a confirmed ghost behind the rail


def test_crossing_tracks_sometimes_swap_ids():
    """Two cars cross in an X: their boxes merge at the crossing and the gated nearest-neighbour
    association then sometimes gives each the other's id, which it keeps from then on."""
    heading, speed = math.atan2(3.0, 6.0), math.hypot(6.0, 3.0)
    outcomes = []
    for seed in range(20):
        per = perception(replace(SensorConfig(), clutter_rate_per_frame=0.0, ghost_prob=0.0),
                         seed=seed)
        msgs = drive(per, 80, lambda k: [(20.0 + 6.0 * k * DT_S, -6.0 + 3.0 * k * DT_S, heading,
                                          speed),
                                         (20.0 + 6.0 * k * DT_S, 6.0 - 3.0 * k * DT_S, -heading,
                                          speed)],
                     ego=(0.0, 0.0, 0.0, 0.0))
        first, last = msgs[20], msgs[-1]
        assert len(first.track_id) == 2 and len(last.track_id) == 2
        rising = first.track_id[np.argmin(first.y_m)]  # the car going left, now on the right
        outcomes.append(bool(last.track_id[np.argmax(last.y_m)] == rising))
    assert any(outcomes) and not all(outcomes)
