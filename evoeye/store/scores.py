"""Table monitor_scores: each evaluated monitor's risk per frame, append-only and idempotent.

Layout: `<root>/warehouse/monitor_scores/part-<utc stamp>-<id>.parquet`, one part per
evaluation (`evaluation_id`), columns as declared in `schemas/warehouse/monitor_scores.sql`
(written and read as every derived table is, `evoeye.store.derived`, keyed by monitor version).
A write locks its version (`key_lock`), skips every (monitor_version, scenario_id) already
stored and writes the rest as one new part, so re-running an evaluation adds nothing and a
killed write leaves no partial part.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from evoeye.paths import DataRoot
from evoeye.store.derived import append_part, part_files, read_parts
from evoeye.store.ingest import refresh_catalog
from evoeye.store.lock import key_lock
from evoeye.store.schema import declared_schema

SCORES_TABLE = "monitor_scores"


def scores_schema() -> pa.Schema:
    """The Arrow schema of monitor_scores, from its DDL."""
    return declared_schema(SCORES_TABLE)


def scores_dir(root: DataRoot) -> Path:
    return root.table_dir(SCORES_TABLE)


@dataclass(frozen=True)
class ScoreRows:
    """Scores of one monitor version on some frames of one logical scenario."""

    monitor_name: str
    monitor_version: str
    logical_scenario: str
    scenario_id: np.ndarray  # (B,) str
    frame: np.ndarray  # (B,) int
    t_s: np.ndarray  # (B,) float
    score: np.ndarray  # (B,) float in [0, 1]

    def __post_init__(self) -> None:
        n = len(self.score)
        if not (len(self.scenario_id) == len(self.frame) == len(self.t_s) == n):
            raise ValueError("scenario_id, frame, t_s and score must have one entry per frame")


@dataclass(frozen=True)
class ScoresWritten:
    """What one `write_scores` call stored (paths relative to the data root)."""

    rows: int
    scenarios: int
    skipped_scenarios: int  # already stored for this monitor version
    part: str | None  # None when there was nothing new


def scored_scenarios(root: DataRoot, monitor_version: str) -> set[str]:
    """The scenario ids that monitor_scores already holds for `monitor_version`."""
    table = read_parts(root, SCORES_TABLE, "monitor_scores_scenarios", key=monitor_version,
                       version=monitor_version)
    return set(table.column("scenario_id").to_pylist())


def read_scores(
    root: DataRoot,
    *,
    monitor_version: str | None = None,
    columns: Sequence[str] | None = None,
) -> pa.Table:
    """Rows of monitor_scores (all, or one monitor version), ordered by version, run, frame."""
    names = list(columns) if columns is not None else scores_schema().names
    unknown = set(names) - set(scores_schema().names)
    if unknown:
        raise KeyError(f"monitor_scores has no column(s) {sorted(unknown)}")
    return read_parts(root, SCORES_TABLE, "monitor_scores_rows", key=monitor_version,
                      version=monitor_version).select(names)


def write_scores(root: DataRoot, rows: ScoreRows) -> ScoresWritten:
    """Append the scores of every run not yet stored for this monitor version, as one part;
    the table's first part also rewrites the DuckDB catalog file, whose view read no part."""
    ids = np.asarray(rows.scenario_id, dtype=object)
    first = not part_files(root.table_dir(SCORES_TABLE))
    with key_lock(root, SCORES_TABLE, [rows.monitor_version]):
        done = scored_scenarios(root, rows.monitor_version)
        keep = np.array([i not in done for i in ids.tolist()], dtype=bool)
        new_ids = set(ids[keep].tolist())
        skipped = len(set(ids.tolist()) & done)
        if not keep.any():
            return ScoresWritten(0, 0, skipped, None)
        n = int(keep.sum())
        part = append_part(root, SCORES_TABLE, {
            "monitor_name": pa.array([rows.monitor_name] * n, pa.string()),
            "monitor_version": pa.array([rows.monitor_version] * n, pa.string()),
            "logical_scenario": pa.array([rows.logical_scenario] * n, pa.string()),
            "scenario_id": pa.array(ids[keep].tolist(), pa.string()),
            "frame": pa.array(np.asarray(rows.frame)[keep], pa.int32()),
            "t_s": pa.array(np.asarray(rows.t_s, dtype=np.float64)[keep], pa.float64()),
            "score": pa.array(np.asarray(rows.score, dtype=np.float32)[keep], pa.float32()),
        }, part_column="evaluation_id", key=rows.monitor_version)
    if first and root.duckdb_file.exists():
        refresh_catalog(root)
    return ScoresWritten(n, len(new_ids), skipped, part)
