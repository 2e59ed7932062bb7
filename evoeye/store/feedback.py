"""Tables feedback and campaign_rounds: the evolution campaign's state, append-only and idempotent.

Layout: `<root>/warehouse/<table>/part-<utc stamp>-<id>.parquet`, columns as declared in
`schemas/warehouse/<table>.sql`. Like monitor_scores (see `scores.py`, whose atomic part writer
this reuses), a write takes the warehouse writer lock, skips the keys already stored —
(monitor_version, scenario_id) for feedback, (campaign_id, round) for rounds — and writes the
rest as one new part, so a killed campaign that re-runs a step adds nothing twice.
"""

from __future__ import annotations

import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime

import duckdb
import numpy as np
import pyarrow as pa

from evoeye.paths import DataRoot
from evoeye.store.lock import WriterLock
from evoeye.store.schema import declared_schema
from evoeye.store.scores import PART_SUFFIX, _write_part

FEEDBACK_TABLE = "feedback"
ROUNDS_TABLE = "campaign_rounds"



def _read(root: DataRoot, table: str, where: str, params: dict, order: str) -> pa.Table:
    """Rows of `table` matching `where` (bound `$params`), or the empty declared table."""
    folder = root.table_dir(table)
    if not any(folder.glob(f"*{PART_SUFFIX}")):
        return declared_schema(table).empty_table()
    con = duckdb.connect()
    try:
        return con.sql(
            f"SELECT * FROM read_parquet($glob) WHERE {where} ORDER BY {order}",
            params={"glob": str(folder / f"*{PART_SUFFIX}"), **params},
        ).to_arrow_table()
    finally:
        con.close()


def _append(root: DataRoot, table: str, columns: dict[str, pa.Array]) -> str:
    """Write one part of `table` (columns in any order, checked against the DDL); its path."""
    stamp = datetime.now(UTC)
    name = f"part-{stamp:%Y%m%dT%H%M%SZ}-{uuid.uuid4().hex[:8]}"
    schema = declared_schema(table)
    n = len(next(iter(columns.values())))
    stamp_col = schema.names[-1]  # written_at / finished_at: each campaign table ends with it
    columns = {**columns, stamp_col: pa.array([stamp] * n, schema.field(stamp_col).type)}
    if "part_id" in schema.names:
        columns["part_id"] = pa.array([name] * n, pa.string())
    out = pa.table([columns[f.name] for f in schema], schema=schema)
    return root.relative(_write_part(root.table_dir(table), name, out))


# -- feedback ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FeedbackRows:
    """f_r of some runs of one logical scenario under one monitor version."""

    logical_scenario: str
    monitor_version: str
    scenario_id: np.ndarray  # (S,) str
    feedback: np.ndarray  # (S,) float in [0, 1]
    n_contexts: np.ndarray  # (S,) int

    def __post_init__(self) -> None:
        if not (len(self.scenario_id) == len(self.feedback) == len(self.n_contexts)):
            raise ValueError("scenario_id, feedback and n_contexts must have one entry per run")


def read_feedback(
    root: DataRoot, monitor_version: str | None = None
) -> pa.Table:
    """Rows of feedback (all, or one monitor version), ordered by version and run."""
    return _read(root, FEEDBACK_TABLE,
                 "$version IS NULL OR monitor_version = $version",
                 {"version": monitor_version}, "monitor_version, scenario_id")


def feedback_of(root: DataRoot, monitor_version: str) -> dict[str, float]:
    """scenario_id → stored f_r under `monitor_version`."""
    t = read_feedback(root, monitor_version)
    return dict(zip(t.column("scenario_id").to_pylist(), t.column("feedback").to_pylist(),
                    strict=True))


def write_feedback(root: DataRoot, rows: FeedbackRows) -> int:
    """Append the feedback of every run not yet stored for this monitor version; rows written."""
    ids = np.asarray(rows.scenario_id, dtype=object)
    with WriterLock(root.writer_lock):
        done = set(feedback_of(root, rows.monitor_version))
        _, first = np.unique(ids, return_index=True)
        keep = np.array([i in set(first) and ids[i] not in done for i in range(len(ids))],
                        dtype=bool)
        n = int(keep.sum())
        if n == 0:
            return 0
        _append(root, FEEDBACK_TABLE, {
            "logical_scenario": pa.array([rows.logical_scenario] * n, pa.string()),
            "scenario_id": pa.array(ids[keep].tolist(), pa.string()),
            "monitor_version": pa.array([rows.monitor_version] * n, pa.string()),
            "feedback": pa.array(np.asarray(rows.feedback, float)[keep], pa.float64()),
            "n_contexts": pa.array(np.asarray(rows.n_contexts)[keep], pa.int32()),
        })
    return n


# -- campaign rounds -----------------------------------------------------------------------------
@dataclass(frozen=True)
class RoundRow:
    """One finished round of a campaign (see schemas/warehouse/campaign_rounds.sql)."""

    campaign_id: str
    logical_scenario: str
    strategy: str
    seed: int
    round: int
    monitor_version: str
    scenario_ids: Sequence[str]
    n_records: int
    simulated_s: float
    train_s: float = 0.0
    metrics: str = ""

    @classmethod
    def from_dict(cls, d: dict) -> RoundRow:
        return cls(**{k: d[k] for k in cls.__dataclass_fields__})


def read_rounds(root: DataRoot, campaign_id: str | None = None
                ) -> list[RoundRow]:
    """The finished rounds of one campaign (or all), in campaign and round order."""
    t = _read(root, ROUNDS_TABLE, "$cid IS NULL OR campaign_id = $cid",
              {"cid": campaign_id}, "campaign_id, round")
    return [RoundRow.from_dict(d) for d in t.to_pylist()]


def write_round(root: DataRoot, row: RoundRow) -> bool:
    """Store a finished round unless (campaign_id, round) is stored already; True if written."""
    with WriterLock(root.writer_lock):
        if any(r.round == row.round for r in read_rounds(root, row.campaign_id)):
            return False
        _append(root, ROUNDS_TABLE, {
            "campaign_id": pa.array([row.campaign_id], pa.string()),
            "logical_scenario": pa.array([row.logical_scenario], pa.string()),
            "strategy": pa.array([row.strategy], pa.string()),
            "seed": pa.array([row.seed], pa.int64()),
            "round": pa.array([row.round], pa.int32()),
            "monitor_version": pa.array([row.monitor_version], pa.string()),
            "scenario_ids": pa.array([list(row.scenario_ids)], pa.list_(pa.string())),
            "n_records": pa.array([row.n_records], pa.int32()),
            "simulated_s": pa.array([row.simulated_s], pa.float64()),
            "train_s": pa.array([row.train_s], pa.float64()),
            "metrics": pa.array([row.metrics], pa.string()),
        })
    return True
