"""A run log's windows straight from MCAP: the numpy twin of the warehouse's labels and windows."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.store import ingest, load_windows
from evoeye.store.log_windows import frame_labels, read_logged_run
from evoeye.store.windows import context_rows


def test_frame_labels_and_contexts_follow_the_definitions() -> None:
    t = np.arange(10) * 0.5
    hit = np.zeros(10, bool)
    hit[6:] = True  # tau_col = 3.0 s
    assert frame_labels(t, hit, 1.0).tolist() == [0, 0, 0, 0, 1, 1, 0, 0, 0, 0]
    assert frame_labels(t, np.zeros(10, bool), 1.0).sum() == 0
    ctx, mask = context_rows(np.zeros(3, np.int64), 2)  # one run of 3 frames, L = 2
    assert ctx.tolist() == [[0, 0], [0, 1], [1, 2]]
    assert mask.tolist() == [[False, True], [True, True], [True, True]]


@pytest.mark.parametrize("context_len", [1, 5])
def test_log_windows_equal_the_warehouse_windows_of_the_ingested_runs(root: DataRoot, add_run,
                                                                      context_len: int) -> None:
    logs = {"hit": add_run("hit", n_frames=40, collision_frame=31, seed=1),
            "safe": add_run("safe", n_frames=25, seed=2)}
    ingest(root)
    for sid, log in logs.items():
        mine = read_logged_run(log, context_len=context_len, horizon_s=1.0)
        assert mine.ok and mine.metadata["scenario_id"] == sid
        ref = load_windows(root, [sid], context_len=context_len, horizon_s=1.0)
        assert len(mine.windows) == len(ref) == (31 if sid == "hit" else 25)  # pre-collision
        assert mine.windows.label.sum() == (20 if sid == "hit" else 0)  # 1 s at 20 Hz
        for name in ("label", "context_mask", "frame", "t_s", "ego_xy_m"):
            np.testing.assert_array_equal(getattr(mine.windows, name), getattr(ref, name),
                                          err_msg=name)
        for name, a in mine.windows.arrays().items():
            np.testing.assert_array_equal(a, ref.arrays()[name], err_msg=name)
