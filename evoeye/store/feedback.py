"""Tables feedback, campaign_rounds and committee: an evolution campaign's state, append-only
and idempotent.

Layout: `<root>/warehouse/<table>/part-<utc stamp>-<id>.parquet`, columns as declared in
`schemas/warehouse/<table>.sql`, written and read as every derived table is
(`evoeye.store.derived`): feedback keyed by monitor version, rounds and committees by campaign.
A write locks its key (`key_lock`: writers of other keys, e.g. other campaigns, go on in
parallel), skips the rows already stored — (monitor_version, feedback_mode, scenario_id) for
feedback, (campaign_id, round) for rounds and committees — and writes the rest as one new part,
so a killed campaign that re-runs a step adds nothing twice. Feedback written before the
feedback_mode column existed (prior-corrected rows keyed `<version>+prior`) is read as if
written now (warehouse/queries/feedback_rows.sql).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from evoeye.paths import DataRoot
from evoeye.store.derived import append_part, read_parts
from evoeye.store.lock import key_lock

FEEDBACK_TABLE = "feedback"
ROUNDS_TABLE = "campaign_rounds"
COMMITTEE_TABLE = "committee"


# -- feedback ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FeedbackRows:
    """f_r of some runs of one logical scenario under one monitor version and feedback mode."""

    logical_scenario: str
    monitor_version: str
    feedback_mode: str  # "raw" or "prior-corrected" (evoeye.evolve.campaign.config)
    scenario_id: np.ndarray  # (S,) str
    feedback: np.ndarray  # (S,) float in [0, 1]
    n_contexts: np.ndarray  # (S,) int

    def __post_init__(self) -> None:
        if not (len(self.scenario_id) == len(self.feedback) == len(self.n_contexts)):
            raise ValueError("scenario_id, feedback and n_contexts must have one entry per run")

    @classmethod
    def finite(cls, logical_scenario: str, monitor_version: str, feedback_mode: str, ids,
               values, n_contexts=None) -> FeedbackRows:
        """The rows of the runs whose value is finite (`n_contexts` default 0)."""
        ids, values = np.asarray(ids, dtype=object), np.asarray(values, float)
        keep = np.isfinite(values)
        n = np.zeros(len(ids), int) if n_contexts is None else np.asarray(n_contexts)
        return cls(logical_scenario, monitor_version, feedback_mode, ids[keep], values[keep],
                   n[keep])


def read_feedback(root: DataRoot, monitor_version: str | None = None,
                  feedback_mode: str | None = None) -> pa.Table:
    """Rows of feedback (all, or of one monitor version and / or mode), ordered by version,
    mode and run."""
    return read_parts(root, FEEDBACK_TABLE, "feedback_rows", key=monitor_version,
                      version=monitor_version, mode=feedback_mode)


def feedback_of(root: DataRoot, monitor_version: str, feedback_mode: str) -> dict[str, float]:
    """scenario_id → stored f_r under `monitor_version` in `feedback_mode`."""
    t = read_feedback(root, monitor_version, feedback_mode)
    return dict(zip(t.column("scenario_id").to_pylist(), t.column("feedback").to_pylist(),
                    strict=True))


def write_feedback(root: DataRoot, rows: FeedbackRows) -> int:
    """Append the feedback of every run not yet stored for this monitor version and mode; rows
    written."""
    ids = np.asarray(rows.scenario_id, dtype=object)
    with key_lock(root, FEEDBACK_TABLE, [rows.monitor_version]):
        done = set(feedback_of(root, rows.monitor_version, rows.feedback_mode))
        _, first = np.unique(ids, return_index=True)
        keep = np.array([i in set(first) and ids[i] not in done for i in range(len(ids))],
                        dtype=bool)
        n = int(keep.sum())
        if n == 0:
            return 0
        append_part(root, FEEDBACK_TABLE, {
            "logical_scenario": pa.array([rows.logical_scenario] * n, pa.string()),
            "scenario_id": pa.array(ids[keep].tolist(), pa.string()),
            "monitor_version": pa.array([rows.monitor_version] * n, pa.string()),
            "feedback_mode": pa.array([rows.feedback_mode] * n, pa.string()),
            "feedback": pa.array(np.asarray(rows.feedback, float)[keep], pa.float64()),
            "n_contexts": pa.array(np.asarray(rows.n_contexts)[keep], pa.int32()),
        }, key=rows.monitor_version)
    return n


# -- campaign rounds -----------------------------------------------------------------------------
@dataclass(frozen=True)
class RoundMetrics:
    """G_r on the fixed Test Set and on G_0's Hard Set (`evoeye.evolve.campaign.assess`), stored
    with its round as JSON. Per set: auroc, auprc (None with one class), frames, unsafe, and
    f1 / recall / precision at each target FPR, keyed `f1@0.05`, … (None where `reachable@0.05`,
    … is False: the thresholds could not reach that target)."""

    version: str
    test: dict[str, Any]
    hard: dict[str, Any]

    def as_dict(self) -> dict[str, Any]:
        return {"version": self.version, "test": dict(self.test), "hard": dict(self.hard)}

    def to_json(self) -> str:
        return json.dumps(self.as_dict())

    @classmethod
    def from_json(cls, text: str) -> RoundMetrics | None:
        """The metrics of a stored round ('' — not assessed — gives None)."""
        return cls(**json.loads(text)) if text else None


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
    metrics: RoundMetrics | None = None

    @classmethod
    def from_dict(cls, d: dict) -> RoundRow:
        values = {k: d[k] for k in cls.__dataclass_fields__}
        return cls(**{**values, "metrics": RoundMetrics.from_json(values["metrics"])})


def read_rounds(root: DataRoot, campaign_id: str | None = None) -> list[RoundRow]:
    """The finished rounds of one campaign (or all), in campaign and round order."""
    t = read_parts(root, ROUNDS_TABLE, "campaign_rounds_rows", key=campaign_id,
                   campaign_id=campaign_id)
    return [RoundRow.from_dict(d) for d in t.to_pylist()]


def write_round(root: DataRoot, row: RoundRow) -> bool:
    """Store a finished round unless (campaign_id, round) is stored already; True if written."""
    with key_lock(root, ROUNDS_TABLE, [row.campaign_id]):
        if any(r.round == row.round for r in read_rounds(root, row.campaign_id)):
            return False
        append_part(root, ROUNDS_TABLE, {
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
            "metrics": pa.array([row.metrics.to_json() if row.metrics else ""], pa.string()),
        }, key=row.campaign_id)
    return True


# -- committees -----------------------------------------------------------------------------------
def read_committee(root: DataRoot, campaign_id: str) -> dict[int, list[str]]:
    """round → the companion monitor versions of one campaign's committee after that round."""
    t = read_parts(root, COMMITTEE_TABLE, "committee_rows", key=campaign_id,
                   campaign_id=campaign_id)
    return {int(r["round"]): list(r["companions"]) for r in t.to_pylist()}


def write_committee(root: DataRoot, campaign_id: str, round_: int,
                    companions: Sequence[str]) -> bool:
    """Store a round's companions unless (campaign_id, round) is stored already; True if
    written."""
    with key_lock(root, COMMITTEE_TABLE, [campaign_id]):
        if round_ in read_committee(root, campaign_id):
            return False
        append_part(root, COMMITTEE_TABLE, {
            "campaign_id": pa.array([campaign_id], pa.string()),
            "round": pa.array([round_], pa.int32()),
            "companions": pa.array([list(companions)], pa.list_(pa.string())),
        }, key=campaign_id)
    return True
