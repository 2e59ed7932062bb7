"""The campaign's tables: feedback keyed by (version, mode, run), typed round metrics, old parts."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.paths import DataRoot
from evoeye.store import Warehouse
from evoeye.store.feedback import (
    FeedbackRows,
    RoundMetrics,
    RoundRow,
    feedback_of,
    read_feedback,
    read_rounds,
    write_feedback,
    write_round,
)
from evoeye.store.schema import declared_schema

IDS = np.array(["r-1", "r-2"], dtype=object)


def rows(mode: str, values: tuple[float, float]) -> FeedbackRows:
    return FeedbackRows("highway-cut-in", "fusion-a", mode, IDS, np.array(values),
                        np.array([10, 20]))


def test_each_feedback_mode_is_stored_apart_and_written_once(root: DataRoot) -> None:
    assert write_feedback(root, rows("raw", (0.1, 0.2))) == 2
    assert write_feedback(root, rows("prior-corrected", (0.3, 0.4))) == 2
    assert write_feedback(root, rows("raw", (0.9, 0.9))) == 0  # stored already
    assert feedback_of(root, "fusion-a", "raw") == {"r-1": 0.1, "r-2": 0.2}
    assert feedback_of(root, "fusion-a", "prior-corrected") == {"r-1": 0.3, "r-2": 0.4}
    t = read_feedback(root)
    assert t.schema.names == declared_schema("feedback").names
    assert t.column("feedback_mode").to_pylist() == ["prior-corrected"] * 2 + ["raw"] * 2


def test_feedback_written_before_the_mode_column_reads_as_now(root: DataRoot) -> None:
    old = pa.table({  # the table as it was: prior-corrected feedback keyed `<version>+prior`
        "logical_scenario": ["highway-cut-in"] * 3,
        "scenario_id": ["r-1", "r-2", "r-1"],
        "monitor_version": ["fusion-a+prior", "fusion-a+prior", "fusion-a"],
        "feedback": [0.3, 0.4, 0.1], "n_contexts": pa.array([10, 20, 10], pa.int32()),
        "part_id": ["part-old"] * 3,
        "written_at": pa.array([datetime(2024, 1, 1, tzinfo=UTC)] * 3,
                               pa.timestamp("us", tz="UTC")),
    })
    root.table_dir("feedback").mkdir(parents=True)
    pq.write_table(old, root.table_dir("feedback") / "part-old.parquet")
    assert feedback_of(root, "fusion-a", "prior-corrected") == {"r-1": 0.3, "r-2": 0.4}
    assert feedback_of(root, "fusion-a", "raw") == {"r-1": 0.1}
    assert write_feedback(root, rows("prior-corrected", (0.7, 0.8))) == 0  # nothing twice
    assert write_feedback(root, rows("raw", (0.7, 0.8))) == 1  # only r-2 is new
    t = read_feedback(root, "fusion-a")
    assert set(t.column("monitor_version").to_pylist()) == {"fusion-a"}
    assert sorted(zip(t.column("feedback_mode").to_pylist(), t.column("scenario_id").to_pylist(),
                      t.column("feedback").to_pylist(), strict=True)) == [
        ("prior-corrected", "r-1", 0.3), ("prior-corrected", "r-2", 0.4), ("raw", "r-1", 0.1),
        ("raw", "r-2", 0.8)]
    columns = "monitor_version, feedback_mode, scenario_id, feedback"  # the view reads as they do
    view = Warehouse(root).read_only_sql(f"SELECT {columns} FROM feedback ORDER BY ALL")
    assert view.to_pylist() == \
        read_feedback(root).select(columns.split(", ")).sort_by(
            [(c, "ascending") for c in columns.split(", ")]).to_pylist()


def test_round_metrics_are_typed_and_round_trip(root: DataRoot) -> None:
    m = RoundMetrics("fusion-b", test={"f1@0.05": 0.25, "auprc": None, "frames": 40},
                     hard={"f1@0.05": 0.0, "auprc": 0.125, "frames": 6})
    assert write_round(root, RoundRow("evo-1", "highway-cut-in", "uniform", 0, 0, "fusion-a",
                                      [], 0, 0.0))
    assert write_round(root, RoundRow("evo-1", "highway-cut-in", "uniform", 0, 1, "fusion-b",
                                      ["r-1"], 1, 12.5, 3.0, m))
    assert not write_round(root, RoundRow("evo-1", "highway-cut-in", "uniform", 0, 1, "x", [],
                                          0, 0.0))
    first, second = read_rounds(root, "evo-1")
    assert first.metrics is None  # not assessed
    assert second.metrics == m and second.metrics.hard["auprc"] == 0.125
    assert list(second.scenario_ids) == ["r-1"] and second.train_s == 3.0
