"""load_windows against a plain numpy reference built from the warehouse views, row by row.

The reference reads every frame through DuckDB (frames, frame_features, runtime_frames), decides
eligibility and labels in numpy from the ground truth, and builds each window by a loop over its
L slots: any divergence of the fast path (Arrow reads, part order, subsets, padding at run
starts, collision tails) shows up as a different array, mask, label or row order.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from evoeye.paths import DataRoot
from evoeye.store import FEATURES, Warehouse, ingest, load_windows
from evoeye.store.features import unpack
from evoeye.store.schema import WarehouseLayoutError
from evoeye.store.windows import context_rows

RUNS = {  # scenario_id: make_episode arguments (several parts, partitions and ingests)
    "r-short": {"n_frames": 3, "seed": 1},
    "r-hit-early": {"n_frames": 9, "collision_frame": 2, "seed": 2},
    "r-hit-first": {"n_frames": 5, "collision_frame": 0, "seed": 3},  # no eligible frame
    "r-long": {"n_frames": 14, "seed": 4, "logical_scenario": "unprotected-intersection"},
    "r-hit-late": {"n_frames": 11, "collision_frame": 8, "seed": 5, "batch": "b001"},
    "r-one": {"n_frames": 1, "seed": 6},
    "r-late-ingest": {"n_frames": 7, "collision_frame": 6, "seed": 7},
}


@pytest.fixture
def varied(root: DataRoot, add_run) -> DataRoot:
    for sid in list(RUNS)[:-1]:
        add_run(sid, **RUNS[sid])
    ingest(root, runs_per_part=2)
    sid = list(RUNS)[-1]
    add_run(sid, **RUNS[sid])
    ingest(root)
    return root


def reference(root: DataRoot, scenario_ids: list[str], context_len: int, horizon_s: float):
    """The windows of `scenario_ids`, by a loop: (arrays, scenario_id, frame, t_s, ego_xy_m)."""
    wh = Warehouse(root)
    frames = wh.sql("SELECT scenario_id, frame, t_s, gt_ego_collision FROM frames "
                    "ORDER BY scenario_id, frame").to_pydict()
    stored = wh.sql("SELECT * FROM frame_features ORDER BY scenario_id, frame")
    loc = wh.sql("SELECT loc_x_m, loc_y_m FROM runtime_frames ORDER BY scenario_id, frame")
    features = unpack(stored, FEATURES).arrays()
    sids = np.array(frames["scenario_id"], dtype=object)
    t_s, hit = np.array(frames["t_s"]), np.array(frames["gt_ego_collision"])
    out = {name: [] for name in (*features, "context_mask", "label")}
    meta = {"scenario_id": [], "frame": [], "t_s": [], "ego_xy_m": []}
    for sid in sorted(scenario_ids):
        rows = np.flatnonzero(sids == sid)
        hits = rows[hit[rows]]
        tau = t_s[hits[0]] if len(hits) else None
        eligible = [r for r in rows if tau is None or tau - t_s[r] > 1e-6]
        for i, r in enumerate(eligible):
            slots = [eligible[max(i - context_len + 1 + k, 0)] for k in range(context_len)]
            for name, arr in features.items():
                out[name].append(arr[slots])
            out["context_mask"].append([i - context_len + 1 + k >= 0 for k in range(context_len)])
            lead = None if tau is None else tau - t_s[r]
            out["label"].append(float(lead is not None and lead <= horizon_s + 1e-6))
            meta["scenario_id"].append(sid)
            meta["frame"].append(frames["frame"][r])
            meta["t_s"].append(t_s[r])
            meta["ego_xy_m"].append([loc["loc_x_m"][r].as_py(), loc["loc_y_m"][r].as_py()])
    return {k: np.array(v) for k, v in out.items()}, meta


def assert_same(windows, expected) -> None:
    arrays, meta = expected
    got = windows.arrays()
    assert set(got) == set(arrays)
    for name, arr in arrays.items():
        assert got[name].dtype == windows.arrays(np.arange(0))[name].dtype
        np.testing.assert_array_equal(got[name], arr.astype(got[name].dtype), err_msg=name)
    assert windows.scenario_id.tolist() == meta["scenario_id"]
    assert windows.frame.tolist() == meta["frame"]
    assert windows.t_s.tolist() == meta["t_s"]
    np.testing.assert_array_equal(windows.ego_xy_m, np.array(meta["ego_xy_m"]).reshape(-1, 2))


@pytest.mark.parametrize("context_len", [1, 3, 5, 12])
def test_every_run_matches_the_reference(varied: DataRoot, context_len: int) -> None:
    ids = list(RUNS)
    w = load_windows(varied, ids, context_len=context_len, horizon_s=0.2)
    assert_same(w, reference(varied, ids, context_len, 0.2))
    assert "r-hit-first" not in set(w.scenario_id)  # collides at once: no eligible frame


def test_a_subset_of_runs_sharing_parts_matches_the_reference(varied: DataRoot) -> None:
    ids = ["r-hit-late", "r-long", "r-short"]  # parts also hold runs that are not selected
    w = load_windows(varied, ids, context_len=4, horizon_s=0.3)
    assert_same(w, reference(varied, ids, 4, 0.3))
    assert len(w.features) == len(w)  # only the selected frames' inputs are kept


def test_a_part_of_the_old_layout_anywhere_is_refused(varied: DataRoot,
                                                      as_layout_1) -> None:
    """Every frame_features part is checked as it is read, not only the one a connection
    checks: one part of layout 1 among new ones is named, never read as floats."""
    for part in sorted(varied.table_dir("frame_features").rglob("*.parquet")):
        kept = part.read_bytes()
        as_layout_1(part)
        assert pa.types.is_list(pq.read_schema(part).field("control").type)
        with pytest.raises(WarehouseLayoutError, match="layout 1; .* re-ingest"):
            load_windows(varied, list(RUNS), context_len=5)
        part.write_bytes(kept)
    assert_same(load_windows(varied, list(RUNS), context_len=5),
                reference(varied, list(RUNS), 5, 3.0))


def test_parts_of_many_row_groups_read_the_same(varied: DataRoot) -> None:
    """A part read back as several record batches, some holding no selected row."""
    for path in varied.table_dir("frame_features").rglob("*.parquet"):
        pq.write_table(pq.read_table(path, partitioning=None), path, row_group_size=2)
    assert pq.ParquetFile(path).num_row_groups > 2
    ids = ["r-hit-late", "r-long", "r-one"]
    assert_same(load_windows(varied, ids, context_len=3), reference(varied, ids, 3, 3.0))


def test_a_missing_feature_part_is_named(varied: DataRoot) -> None:
    part = next(varied.table_dir("frame_features").rglob("*.parquet"))
    part.unlink()
    with pytest.raises(RuntimeError, match="have no frame_features"):
        load_windows(varied, list(RUNS))


def test_context_rows_pad_each_run_with_its_first_row() -> None:
    run_start = np.array([0, 0, 0, 3, 4, 4])  # runs of 3, 1 and 2 rows
    ctx, mask = context_rows(run_start, 3)
    assert ctx.tolist() == [[0, 0, 0], [0, 0, 1], [0, 1, 2], [3, 3, 3], [4, 4, 4], [4, 4, 5]]
    assert mask.tolist() == [[False, False, True], [False, True, True], [True, True, True],
                             [False, False, True], [False, False, True], [False, True, True]]
