"""Monitor inputs of a frame: ego frame, nearest first, truncation, padding, masks."""

from __future__ import annotations

import math

import numpy as np
import pyarrow as pa
import pytest

from evoeye.ads.messages import PLANNING_DECISIONS
from evoeye.store import Warehouse, ingest
from evoeye.store.features import (
    FEATURES,
    PERCEPTION_FEATURES,
    PLAN_FEATURES,
    FeatureSpec,
    frame_features,
    pack,
    unpack,
)
from evoeye.store.records import runtime_table

SPEC = FeatureSpec(max_obstacles=2, pred_points=2, pred_stride=3, plan_points=4, plan_stride=2)
P = {name: i for i, name in enumerate(PERCEPTION_FEATURES)}
Q = {name: i for i, name in enumerate(PLAN_FEATURES)}


def _frames(decisions: list[str | None], obstacles_x: list[list[float]]) -> pa.Table:
    """Frames with the ego at (10, 5) heading +y (pi/2) at 2 m/s; obstacles at x, y."""
    n = len(decisions)
    obs_y = [[25.0, 5.0, -40.0][: len(xs)] for xs in obstacles_x]
    k_raw = 6
    return pa.table({
        "loc_x_m": [10.0] * n, "loc_y_m": [5.0] * n, "loc_heading_rad": [math.pi / 2] * n,
        "loc_speed_mps": [2.0] * n, "loc_accel_mps2": [0.5] * n,
        "obs_x_m": obstacles_x, "obs_y_m": obs_y,
        "obs_heading_rad": [[math.pi / 2] * len(xs) for xs in obstacles_x],
        "obs_vx_mps": [[0.0] * len(xs) for xs in obstacles_x],
        "obs_vy_mps": [[12.0] * len(xs) for xs in obstacles_x],
        "obs_length_m": [[4.0] * len(xs) for xs in obstacles_x],
        "obs_width_m": [[2.0] * len(xs) for xs in obstacles_x],
        "obs_confidence": [[0.9] * len(xs) for xs in obstacles_x],
        # one predicted track per obstacle: straight ahead (+y) one metre per point
        "pred_track_id": [list(range(1, len(xs) + 1)) for xs in obstacles_x],
        "pred_x_m": [[[x] * k_raw for x in xs] for xs in obstacles_x],
        "pred_y_m": [[[y + j + 1 for j in range(k_raw)] for y in ys] for ys in obs_y],
        "plan_decision": decisions,
        "plan_target_speed_mps": [8.0] * n,
        "plan_t_rel_s": [[0.0, 0.1, 0.2, 0.3, 0.4]] * n,
        "plan_x_m": [[10.0] * 5] * n,
        "plan_y_m": [[5.0, 6.0, 7.0, 8.0, float("nan")]] * n,
        "plan_heading_rad": [[math.pi / 2] * 5] * n,
        "plan_speed_mps": [[2.0, 2.1, 2.2, 2.3, 2.4]] * n,
        "plan_accel_mps2": [[0.0] * 5] * n,
        "ctrl_throttle": [0.3] * n, "ctrl_brake": [0.0] * n, "ctrl_steering_rad": [0.01] * n,
        "ctrl_accel_cmd_mps2": [1.0] * n,
    })


def test_perception_is_ego_relative_nearest_first_and_truncated() -> None:
    f = frame_features(_frames(["yield"], [[10.0, 7.0, 10.0]]), SPEC)
    near, far = f.perception[0]
    # (7, 5) is 3 m to the ego's left; (10, 25) is 20 m ahead; (10, -40) is dropped
    assert near[P["dx_m"]] == pytest.approx(0.0, abs=1e-5)
    assert near[P["dy_m"]] == pytest.approx(3.0)
    assert far[P["dx_m"]] == pytest.approx(20.0) and far[P["dy_m"]] == pytest.approx(0.0, abs=1e-5)
    assert far[P["cos_dheading"]] == pytest.approx(1.0)
    # velocity (0, 12) minus the ego's (0, 2): 10 m/s forward in the ego frame
    assert far[P["dvx_mps"]] == pytest.approx(10.0)
    assert far[P["dvy_mps"]] == pytest.approx(0.0, abs=1e-5)
    assert far[P["confidence"]] == pytest.approx(0.9)
    assert f.perception_mask[0].tolist() == [True, True]


def test_missing_obstacles_are_zero_and_masked() -> None:
    f = frame_features(_frames(["cruise", "cruise"], [[10.0], []]), SPEC)
    assert f.perception_mask.tolist() == [[True, False], [False, False]]
    assert not f.perception[0, 1].any() and not f.perception[1].any()
    assert f.prediction_mask.tolist() == [[True, False], [False, False]]


def test_prediction_keeps_strided_points_in_the_ego_frame() -> None:
    f = frame_features(_frames(["cruise"], [[10.0, 7.0]]), SPEC)
    # raw points 2 and 5 (stride 3) of the track starting 20 m ahead: 23 m and 26 m ahead
    np.testing.assert_allclose(f.prediction[0, 1, :, 0], [23.0, 26.0], rtol=1e-6)
    np.testing.assert_allclose(f.prediction[0, 0, :, 1], [3.0, 3.0], rtol=1e-6)


def test_plan_is_strided_padded_with_its_last_point_and_finite() -> None:
    f = frame_features(_frames(["follow"], [[10.0]]), SPEC)
    plan = f.plan[0]
    # raw points 0, 2, 4 exist; slot 3 (raw 6) repeats raw 4 and is masked
    np.testing.assert_allclose(plan[:, Q["t_rel_s"]], [0.0, 0.2, 0.4, 0.4], rtol=1e-6)
    np.testing.assert_allclose(plan[:3, Q["dx_m"]], [0.0, 2.0, 0.0], atol=1e-5)  # NaN -> 0
    assert f.plan_mask[0].tolist() == [True, True, True, False]
    assert np.isfinite(plan).all()


def test_plan_info_one_hot_and_control() -> None:
    f = frame_features(_frames(["yield", "teleport"], [[10.0], [10.0]]), SPEC)
    hot = f.plan_info[:, 1:]
    assert hot[0].tolist() == [float(d == "yield") for d in PLANNING_DECISIONS]
    assert not hot[1].any()  # an unknown decision has no hot entry
    assert f.plan_info[0, 0] == pytest.approx(8.0)
    np.testing.assert_allclose(f.control[0], [0.3, 0.0, 0.01, 1.0, 2.0, 0.5], rtol=1e-6)


def test_pack_then_unpack_is_the_identity() -> None:
    f = frame_features(_frames(["yield", "cruise"], [[10.0, 7.0, 10.0], [7.0]]), SPEC)
    g = unpack(pa.table(pack(f)), SPEC)
    for name, arr in f.arrays().items():
        np.testing.assert_array_equal(getattr(g, name), arr, err_msg=name)


def test_unpack_refuses_another_spec() -> None:
    f = frame_features(_frames(["yield"], [[10.0]]), SPEC)
    with pytest.raises(ValueError, match="another FeatureSpec"):
        unpack(pa.table(pack(f)), FeatureSpec())


def test_runtime_messages_give_the_inputs_stored_at_ingest(
    root, episode_factory, log_writer
) -> None:
    """Training and runtime share one feature path: live messages → the stored inputs."""
    episode = episode_factory("live", n_frames=15, seed=9)
    log_writer(root, episode)
    ingest(root)
    stored = unpack(Warehouse(root).sql("SELECT * FROM frame_features ORDER BY frame"), FEATURES)
    live = frame_features(runtime_table([f.messages for f in episode.frames]), FEATURES)
    for name, arr in stored.arrays().items():
        np.testing.assert_allclose(getattr(live, name), arr, rtol=1e-6, atol=1e-5, err_msg=name)


def test_prediction_takes_each_obstacles_most_probable_mode_only() -> None:
    t = _frames(["cruise"], [[10.0, 7.0]])
    # obstacle 1 gets a second, less probable mode (listed after its first), nearer to the ego
    # than its first mode: without the rule it would take obstacle 1's slot
    t = t.set_column(t.schema.get_field_index("pred_track_id"), "pred_track_id",
                     pa.array([[1, 1, 2]]))
    x = t.column("pred_x_m").to_pylist()[0]
    y = t.column("pred_y_m").to_pylist()[0]
    t = t.set_column(t.schema.get_field_index("pred_x_m"), "pred_x_m",
                     pa.array([[x[0], [v - 5.0 for v in x[0]], x[1]]]))
    t = t.set_column(t.schema.get_field_index("pred_y_m"), "pred_y_m",
                     pa.array([[y[0], [v - 15.0 for v in y[0]], y[1]]]))
    f = frame_features(t, SPEC)
    assert f.prediction_mask[0].tolist() == [True, True]
    # no slot holds the second mode (5 m to the left): obstacle 1 (0 m) and 2 (3 m) do
    lateral = sorted(float(v) for v in f.prediction[0, :, 0, 1])
    assert lateral == pytest.approx([0.0, 3.0], abs=1e-5)


@pytest.mark.parametrize("n_obstacles", [0, 1, 6])
def test_live_messages_give_exactly_the_inputs_stored_at_ingest(
    root, episode_factory, log_writer, n_obstacles
) -> None:
    """The run-time source (MessageSignals: one frame's messages, as the ADS sends them or as
    decoded from its log) feeds the one feature code the very numbers ingest stored."""
    from evoeye.monitor.replay import log_frames
    from evoeye.store.records import MessageSignals

    episode = episode_factory("live", n_frames=12, seed=4, n_obstacles=n_obstacles)
    episode.frames[3].messages.plan.decision = "teleport"  # not a known decision: no hot entry
    log = log_writer(root, episode)
    ingest(root)
    stored = unpack(Warehouse(root).sql("SELECT * FROM frame_features ORDER BY frame"), FEATURES)
    for frames in ([f.messages for f in episode.frames], log_frames(log)):
        for i, messages in enumerate(frames):
            live = frame_features(MessageSignals(messages), FEATURES)
            through_arrow = frame_features(runtime_table([messages]), FEATURES)
            for name, arr in stored.arrays().items():
                np.testing.assert_array_equal(getattr(live, name)[0], arr[i], err_msg=name)
                np.testing.assert_array_equal(getattr(through_arrow, name)[0], arr[i])
    assert stored.perception_mask.sum(axis=1).max() == n_obstacles
    assert not stored.plan_info[3, 1:].any() and stored.plan_info[4, 1:].sum() == 1


def test_obstacles_at_equal_distance_keep_their_order_and_unknown_distances_come_last() -> None:
    t = _frames(["cruise"], [[10.0, 7.0, 13.0]])  # 20 m ahead; 3 m left; 3 m right
    x = [float("nan"), 7.0, 13.0]
    t = t.set_column(t.schema.get_field_index("obs_x_m"), "obs_x_m", pa.array([x]))
    t = t.set_column(t.schema.get_field_index("obs_y_m"), "obs_y_m", pa.array([[5.0] * 3]))
    f = frame_features(t, SPEC)
    # the NaN obstacle has no distance: it is dropped; the tie keeps the message order
    assert f.perception[0, :, P["dy_m"]] == pytest.approx([3.0, -3.0])
    assert f.perception_mask[0].tolist() == [True, True]


def test_a_batch_of_frames_gives_each_frames_own_features() -> None:
    """One definition for ingest (N frames) and run time (one): a frame's row never depends
    on the frames beside it, non-finite inputs included."""
    t = _frames(["yield", "cruise", "follow"], [[10.0, 7.0, 10.0], [], [7.0, float("inf")]])
    t = t.set_column(t.schema.get_field_index("loc_speed_mps"), "loc_speed_mps",
                     pa.array([2.0, float("nan"), 3.0]))
    batch = frame_features(t, SPEC)
    for i in range(len(t)):
        alone = frame_features(t.slice(i, 1), SPEC)
        for name, arr in batch.arrays().items():
            np.testing.assert_array_equal(getattr(alone, name)[0], arr[i], err_msg=name)
    assert np.isfinite(batch.perception).all() and np.isfinite(batch.control).all()
    assert batch.control[1, 4] == 0.0  # the NaN ego speed
