"""Perception end to end: latency, track management, the Kalman filter, occlusion."""

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
        out.append(per.perceive(make_scene(t, [ego_row, *car_at(k)]), ego_at(*ego_row[:2])))
    return out


def test_reported_position_lags_the_truth_by_speed_times_latency():
    speed = 20.0
    for latency, lag in ((0.1, speed * 0.1), (0.0, 0.0)):
        per = perception(ideal_sensor(latency_s=latency))
        msgs = drive(per, 40, lambda k: [(30.0 + speed * k * DT_S, 4.0, 0.0, speed)])
        true_x = 30.0 + speed * 39 * DT_S
        assert len(msgs[-1].track_id) == 1
        assert abs((true_x - msgs[-1].x_m[0]) - lag) < 0.05


def test_nothing_is_published_before_the_latency_and_the_confirmation():
    per = perception(ideal_sensor(latency_s=0.1), TrackerConfig(confirm_hits=3))
    msgs = drive(per, 6, lambda k: [(30.0, 4.0, 0.0, 0.0)])
    counts = [len(m.track_id) for m in msgs]
    # detections of frame 0 reach the tracker at frame 2; the 3rd hit comes at frame 4
    assert counts == [0, 0, 0, 0, 1, 1]


def test_track_id_is_stable_and_a_new_one_is_issued_after_a_long_absence():
    config = TrackerConfig(max_coast_frames=10)
    per = perception(SensorConfig(detect_prob_far=0.9), config, seed=5)

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
    per = perception(SensorConfig(detect_prob_far=1.0, detect_prob_near=1.0), seed=2)
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
