"""A run log's labelled windows straight from its MCAP file: the numpy twin of the warehouse's SQL.

The same conversion the warehouse makes, without ingesting: the log's frames as ingest writes
them (`frames_table` → `frame_features`), then eligible frames and labels as the SQL builds them
(`eligible_frames` and `frame_labels_h`, warehouse/views/05_frame_labels.sql) and the contexts
by `load_windows`' own `context_rows`, so a run's windows are bit-identical to those
`load_windows` returns once it is ingested (tests/store/test_log_windows.py checks it). The
evolution campaign scores each freshly simulated run this way: reading the log (not the
in-memory Episode) makes a new run and one found on disk by a resumed campaign go through the
same code.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from evoeye.log import read_run
from evoeye.store.features import FEATURES, frame_features
from evoeye.store.records import frames_table
from evoeye.store.windows import Windows, context_rows

LABEL_EPS_S = 1e-6  # as eligible_frames / frame_labels_h: frame times sit on a float 20 Hz grid


@dataclass(frozen=True)
class LoggedRun:
    """What the loop needs from one run log: its metadata (outcome) and its frames."""

    path: Path
    metadata: dict[str, Any]
    windows: Windows | None  # None for a run without frames

    @property
    def ok(self) -> bool:
        return self.metadata["status"] == "ok"

    @property
    def duration_s(self) -> float:
        return float(self.metadata["duration_s"])


def eligible_frames(t_s: np.ndarray, collided: np.ndarray) -> np.ndarray:
    """(N,) bool, as the view eligible_frames: frames strictly before the first collided frame
    (all frames of a run without one)."""
    hit = np.flatnonzero(collided)
    if len(hit) == 0:
        return np.ones(len(t_s), bool)
    return t_s[hit[0]] - t_s > LABEL_EPS_S


def frame_labels(t_s: np.ndarray, collided: np.ndarray, horizon_s: float) -> np.ndarray:
    """y_t (Definition 1): 1 iff 0 < tau_col − t ≤ H, tau_col the first collided frame's time."""
    hit = np.flatnonzero(collided)
    if len(hit) == 0:
        return np.zeros(len(t_s), np.int8)
    lead = t_s[hit[0]] - t_s
    return ((lead > LABEL_EPS_S) & (lead <= horizon_s + LABEL_EPS_S)).astype(np.int8)


def read_logged_run(path: str | Path, context_len: int, horizon_s: float) -> LoggedRun:
    """A run log's metadata and its labelled windows, as the warehouse would build them (one per
    eligible frame; None if the run has none)."""
    run = read_run(path)
    meta = dict(run.metadata)
    sid = str(meta["scenario_id"])
    frames = frames_table(run, sid, "in-memory")
    t_s = frames.column("t_s").to_numpy()
    collided = frames.column("gt_ego_collision").to_numpy(zero_copy_only=False)
    keep = eligible_frames(t_s, collided)
    labels = frame_labels(t_s, collided, horizon_s)[keep]
    frames, t_s = frames.filter(pa.array(keep)), t_s[keep]
    n = frames.num_rows
    if n == 0:
        return LoggedRun(Path(path), meta, None)
    ctx, mask = context_rows(np.zeros(n, np.int64), context_len)  # one run, from row 0
    xy = np.stack([frames.column(c).to_numpy(zero_copy_only=False).astype(np.float64)
                   for c in ("loc_x_m", "loc_y_m")], axis=1)  # (N, 2)
    windows = Windows(
        frame_features(frames, FEATURES), ctx, mask, labels, np.full(n, sid, dtype=object),
        frames.column("frame").to_numpy().astype(np.int32), t_s, horizon_s, FEATURES, xy,
    )
    return LoggedRun(Path(path), meta, windows)
