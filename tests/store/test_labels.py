"""Frame labels, paper Definition 1: y_t = 1 iff 0 < tau_col - tau_t <= H."""

from __future__ import annotations

import pytest

from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest


@pytest.fixture
def labelled(root: DataRoot, add_run) -> Warehouse:
    # 20 Hz; the ego collides at frame 120 (tau_col = 6.0 s) and stays in collision after it
    add_run("hit", n_frames=160, collision_frame=120, seed=1)
    add_run("safe", n_frames=80, seed=2)
    ingest(root)
    return Warehouse(root)


def _positives(wh: Warehouse, sql: str, **params) -> list[int]:
    rows = wh.sql(sql, params).to_pylist()
    return [r["frame"] for r in rows if r["label"] == 1]


def test_view_uses_h_3_and_excludes_the_collision_frame(labelled: Warehouse) -> None:
    sql = "SELECT frame, label FROM frame_labels WHERE scenario_id = 'hit' ORDER BY frame"
    # 0 < 6.0 - t <= 3  <=>  3.0 <= t < 6.0  <=>  frames 60 .. 119
    assert _positives(labelled, sql) == list(range(60, 120))


@pytest.mark.parametrize(("h", "first"), [(1.0, 100), (3.0, 60), (0.05, 119)])
def test_macro_takes_any_horizon(labelled: Warehouse, h: float, first: int) -> None:
    sql = ("SELECT frame, label FROM frame_labels_h($h) WHERE scenario_id = 'hit' "
           "ORDER BY frame")
    assert _positives(labelled, sql, h=h) == list(range(first, 120))


def test_collision_frame_and_later_frames_have_no_label(labelled: Warehouse) -> None:
    rows = labelled.sql(
        "SELECT frame, label, collision_time_s FROM frame_labels_h(100.0) "
        "WHERE scenario_id = 'hit' AND frame >= 119 ORDER BY frame"
    ).to_pylist()
    assert [(r["frame"], r["label"]) for r in rows] == [(119, 1)]
    assert rows[0]["collision_time_s"] == pytest.approx(6.0)
    # the log keeps its tail for viewing: frames 120 … 159 are in frames, not eligible
    n = labelled.sql("SELECT count(*) AS n FROM frames WHERE scenario_id = 'hit'").to_pylist()
    eligible = labelled.sql("SELECT max(frame) AS last, count(*) AS n FROM eligible_frames "
                            "WHERE scenario_id = 'hit'").to_pylist()
    assert n == [{"n": 160}] and eligible == [{"last": 119, "n": 120}]


def test_runs_without_collision_are_all_safe(labelled: Warehouse) -> None:
    rows = labelled.sql(
        "SELECT count(*) AS n, sum(label) AS pos, max(collision_time_s) AS tau "
        "FROM frame_labels_h(1000.0) WHERE scenario_id = 'safe'"
    ).to_pylist()[0]
    assert rows == {"n": 80, "pos": 0, "tau": None}


@pytest.mark.parametrize("h", [0.05, 1.0, 3.0, 5.95, 6.0, 100.0])
def test_windows_take_the_views_frames_and_labels(labelled: Warehouse, h: float) -> None:
    """load_windows decides eligibility and labels in numpy (evoeye.store.labels): the very
    frames and labels of the views, also where tau_col − t falls on H."""
    from evoeye.store import load_windows

    sql = labelled.sql("SELECT scenario_id, frame, t_s, label FROM frame_labels_h($h) "
                       "ORDER BY scenario_id, frame", {"h": h}).to_pydict()
    w = load_windows(labelled.root, context_len=1, horizon_s=h)
    assert w.scenario_id.tolist() == sql["scenario_id"]
    assert w.frame.tolist() == sql["frame"] and w.t_s.tolist() == sql["t_s"]
    assert w.label.tolist() == sql["label"] and sum(sql["label"]) > 0
