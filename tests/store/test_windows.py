"""Contexts c_t (Definition 2) out of SQL: padding, order, labels, tensors."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from evoeye.paths import DataRoot
from evoeye.store import FEATURES, RunFilter, Warehouse, ingest, load_windows
from evoeye.store.features import CONTROL_FEATURES

THROTTLE = CONTROL_FEATURES.index("throttle")  # the fixture writes throttle = frame / 1000


@pytest.fixture
def two_runs(root: DataRoot, add_run) -> DataRoot:
    add_run("a", n_frames=12, collision_frame=10, seed=1)
    add_run("b", n_frames=7, seed=2, round=2)
    ingest(root)
    return root


def _slot_frames(windows, index=None) -> np.ndarray:
    """(b, L) frame index held in each context slot, read back from the control features."""
    control = windows.arrays(index)["control"]
    return np.rint(control[..., THROTTLE] * 1000).astype(int)


def test_l5_windows_hold_the_last_five_frames_in_order_padded_at_the_start(two_runs) -> None:
    w = load_windows(two_runs, context_len=5)
    assert len(w) == 17 and w.context_len == 5  # a: frames 0 … 9, before its collision; b: 7
    assert list(w.scenario_id[:10]) == ["a"] * 10 and list(w.frame[:10]) == list(range(10))
    slots = _slot_frames(w)
    for i, t in enumerate(w.frame):
        expected = [max(0, t - 4 + k) for k in range(5)]  # m_max(1, t-L+1+k), 0-based
        assert list(slots[i]) == expected
        assert list(w.context_mask[i]) == [t - 4 + k >= 0 for k in range(5)]
    # run b starts fresh: its first window repeats b's first frame, never a's last
    first_b = int(np.flatnonzero(w.scenario_id == "b")[0])
    assert list(slots[first_b]) == [0] * 5
    assert list(w.context_mask[first_b]) == [False] * 4 + [True]


def test_l1_windows_are_single_frames(two_runs) -> None:
    w = load_windows(two_runs, context_len=1)
    assert w.context.shape == (17, 1) and w.context_mask.all()
    assert list(_slot_frames(w)[:, 0]) == list(w.frame)


def test_no_frame_at_or_after_the_collision_is_a_window(two_runs) -> None:
    wh = Warehouse(two_runs)
    tails = wh.sql("SELECT scenario_id, frame FROM frames WHERE gt_ego_collision").to_pylist()
    assert {(r["scenario_id"], r["frame"]) for r in tails} == {("a", 10), ("a", 11)}
    for L in (1, 5):
        w = load_windows(two_runs, context_len=L, horizon_s=100.0)
        a = w.scenario_id == "a"
        assert w.frame[a].max() == 9 and w.label[a].all()  # every frame before it is unsafe
        assert _slot_frames(w).max() <= 11 and (_slot_frames(w)[a] <= 9).all()


def test_windows_carry_the_localization_position(two_runs) -> None:
    w = load_windows(two_runs, context_len=2)
    loc = Warehouse(two_runs).sql(
        "SELECT loc_x_m, loc_y_m FROM runtime_frames ORDER BY scenario_id, frame").to_pydict()
    # frames of a from its collision on are not windows
    keep = [i for i in range(19) if not 10 <= i < 12]
    assert w.ego_xy_m.shape == (17, 2)
    np.testing.assert_allclose(w.ego_xy_m[:, 0], np.array(loc["loc_x_m"])[keep])
    np.testing.assert_allclose(w.ego_xy_m[:, 1], np.array(loc["loc_y_m"])[keep])
    np.testing.assert_array_equal(w.subset(np.array([3, 12])).ego_xy_m, w.ego_xy_m[[3, 12]])


def test_labels_follow_definition_1(two_runs) -> None:
    w = load_windows(two_runs, context_len=3, horizon_s=0.1)
    a = w.scenario_id == "a"
    # collision at frame 10 (0.5 s): 0 < 0.5 - t <= 0.1 -> frames 8 and 9
    assert list(w.frame[a][w.label[a] == 1]) == [8, 9]
    assert w.label[~a].sum() == 0


def test_batch_gives_torch_tensors_with_documented_shapes(two_runs) -> None:
    w = load_windows(two_runs, context_len=5)
    b = w.batch(np.array([0, 5, 13]))
    n, k, p = FEATURES.max_obstacles, FEATURES.pred_points, FEATURES.plan_points
    assert b.perception.shape == (3, 5, n, 9) and b.perception.dtype == torch.float32
    assert b.perception_mask.shape == (3, 5, n) and b.perception_mask.dtype == torch.bool
    assert b.prediction.shape == (3, 5, n, k, 2)
    assert b.plan.shape == (3, 5, p, 7) and b.plan_mask.shape == (3, 5, p)
    assert b.plan_info.shape == (3, 5, 6) and b.control.shape == (3, 5, 6)
    assert b.context_mask.shape == (3, 5) and b.label.shape == (3,)
    assert b.perception_mask[:, -1].sum(dim=-1).tolist() == [4, 4, 4]  # 4 obstacles per frame
    assert torch.equal(b.label, torch.from_numpy(w.label[[0, 5, 13]].astype(np.float32)))


def test_run_subsets_select_whole_runs(two_runs) -> None:
    assert set(load_windows(two_runs, RunFilter(min_round=1)).scenario_id) == {"b"}
    assert set(load_windows(two_runs, RunFilter(collided=True)).scenario_id) == {"a"}
    assert set(load_windows(two_runs, ["b"]).scenario_id) == {"b"}
    sql = "SELECT scenario_id FROM scenarios WHERE n_frames > 10"
    assert set(load_windows(two_runs, sql).scenario_id) == {"a"}
    assert len(load_windows(two_runs, RunFilter(logical_scenario="nowhere"))) == 0


def test_subset_shares_features_and_keeps_contexts(two_runs) -> None:
    w = load_windows(two_runs, context_len=2)
    sub = w.subset(w.scenario_id == "b")
    assert sub.features is w.features and len(sub) == 7
    assert list(_slot_frames(sub)[:, 1]) == list(range(7))


def test_windows_read_no_ground_truth(two_runs) -> None:
    columns = Warehouse(two_runs).sql("SELECT * FROM runtime_frames LIMIT 0").column_names
    assert "ctrl_throttle" in columns
    assert not [c for c in columns if c.startswith("gt_")]


def test_bad_context_or_horizon_is_refused(two_runs) -> None:
    with pytest.raises(ValueError, match="at least 1"):
        load_windows(two_runs, context_len=0)
    with pytest.raises(ValueError, match="positive"):
        load_windows(two_runs, horizon_s=0.0)
