"""Table monitor_scores: each evaluated monitor's risk per frame, append-only and idempotent.

Layout: `<root>/warehouse/monitor_scores/part-<utc stamp>-<id>.parquet`, one part per
evaluation, columns as declared in `schemas/warehouse/monitor_scores.sql`. A write takes the
warehouse writer lock, skips every (monitor_version, scenario_id) already stored and writes the
rest as one new part (temporary file, fsync, rename), so re-running an evaluation adds nothing
and a killed write leaves no partial part. The table lives beside the ingested tables but is
not one of them (its parts have no `scenarios` twin), so it has its own reader here.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import duckdb
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.atomic import atomic_file, fsync_dir
from evoeye.paths import DataRoot
from evoeye.store.lock import WriterLock
from evoeye.store.schema import canonical_schema, declared_schema

SCORES_TABLE = "monitor_scores"
PART_SUFFIX = ".parquet"


def scores_schema() -> pa.Schema:
    """The Arrow schema of monitor_scores, from its DDL."""
    return declared_schema(SCORES_TABLE)


def scores_dir(root: DataRoot) -> Path:
    return root.table_dir(SCORES_TABLE)


def _parts_glob(root: DataRoot) -> str | None:
    folder = scores_dir(root)
    return str(folder / f"*{PART_SUFFIX}") if any(folder.glob(f"*{PART_SUFFIX}")) else None


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
    table = read_scores(root, monitor_version=monitor_version, columns=("scenario_id",))
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
    glob = _parts_glob(root)
    if glob is None:
        return scores_schema().empty_table().select(names)
    select = ", ".join(names)  # validated column names, never values
    con = duckdb.connect()
    try:
        return con.sql(
            f"SELECT {select} FROM read_parquet($glob) "
            "WHERE $version IS NULL OR monitor_version = $version "
            "ORDER BY monitor_version, scenario_id, frame",
            params={"glob": glob, "version": monitor_version},
        ).to_arrow_table()
    finally:
        con.close()


def _write_part(folder: Path, name: str, table: pa.Table) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    final = folder / f"{name}{PART_SUFFIX}"
    tmp = folder / f".{name}{PART_SUFFIX}.{os.getpid()}.tmp"
    with atomic_file(final, tmp) as f:
        pq.write_table(table, f, compression="zstd")
    fsync_dir(folder)
    return final


def write_scores(root: DataRoot, rows: ScoreRows) -> ScoresWritten:
    """Append the scores of every run not yet stored for this monitor version, as one part."""
    ids = np.asarray(rows.scenario_id, dtype=object)
    with WriterLock(root.writer_lock):
        done = scored_scenarios(root, rows.monitor_version)
        keep = np.array([i not in done for i in ids.tolist()], dtype=bool)
        new_ids = set(ids[keep].tolist())
        skipped = len(set(ids.tolist()) & done)
        if not keep.any():
            return ScoresWritten(0, 0, skipped, None)
        stamp = datetime.now(UTC)
        name = f"part-{stamp:%Y%m%dT%H%M%SZ}-{uuid.uuid4().hex[:8]}"
        n = int(keep.sum())
        table = pa.table(
            {
                "monitor_name": pa.array([rows.monitor_name] * n, pa.string()),
                "monitor_version": pa.array([rows.monitor_version] * n, pa.string()),
                "logical_scenario": pa.array([rows.logical_scenario] * n, pa.string()),
                "scenario_id": pa.array(ids[keep].tolist(), pa.string()),
                "frame": pa.array(np.asarray(rows.frame)[keep], pa.int32()),
                "t_s": pa.array(np.asarray(rows.t_s, dtype=np.float64)[keep], pa.float64()),
                "score": pa.array(np.asarray(rows.score, dtype=np.float32)[keep], pa.float32()),
                "evaluation_id": pa.array([name] * n, pa.string()),
                "scored_at": pa.array([stamp] * n, scores_schema().field("scored_at").type),
            }
        )
        if canonical_schema(table.schema) != scores_schema():
            raise ValueError(f"monitor_scores part does not match the DDL:\n{table.schema}")
        path = _write_part(scores_dir(root), name, table)
    return ScoresWritten(n, len(new_ids), skipped, root.relative(path))
