"""A run log's labelled windows straight from its MCAP file: the numpy twin of the warehouse's SQL.

The same conversion the warehouse makes, without ingesting: the log's frames as ingest writes
them (`frames_table` → `frame_features`), then eligible frames and labels as the SQL builds them
(`evoeye.store.labels`, the twin of warehouse/views/05_frame_labels.sql) and the contexts
by `load_windows`' own `context_rows`, so a run's windows are bit-identical to those
`load_windows` returns once it is ingested (tests/store/test_log_windows.py checks it). The
evolution campaign scores each freshly simulated run this way, converting the Episode it just
logged (`episode_run`: its messages as the writer encoded them, not read back, ≈ 4× cheaper)
and a run a resumed campaign finds on disk from its log (`read_logged_run`); the two give the
same frames, features and windows (tests/store/test_episode_frames.py). The conversion is kept
(`LoggedRun.frames`, `.features`) and ingested as it is (`evoeye.store.ingest.ingest_batch`):
one conversion per log.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from evoeye.log import read_run
from evoeye.log.episode_log import EpisodeLog
from evoeye.sim.episode import Episode
from evoeye.store.features import FEATURES, FrameFeatures, frame_features
from evoeye.store.labels import eligible_frames, frame_labels
from evoeye.store.records import RunSource, frames_table
from evoeye.store.windows import Windows, context_rows

UNCOMMITTED = "in-memory"  # the ingest_id of a conversion not yet written to a part


@dataclass(frozen=True)
class LoggedRun:
    """One run log converted: its metadata (outcome), its frames and their features as ingest
    writes them, and its labelled windows."""

    path: Path
    metadata: dict[str, Any]
    frames: pa.Table  # every frame, the frames file schema (ingest_id UNCOMMITTED)
    features: FrameFeatures  # of every frame, in frame order
    windows: Windows | None  # eligible frames only; None for a run without any

    @property
    def ok(self) -> bool:
        return self.metadata["status"] == "ok"

    @property
    def duration_s(self) -> float:
        return float(self.metadata["duration_s"])


def read_logged_run(path: str | Path, context_len: int, horizon_s: float) -> LoggedRun:
    """A run log's metadata and its labelled windows, as the warehouse would build them (one per
    eligible frame; None if the run has none)."""
    return convert_run(read_run(path), Path(path), context_len, horizon_s)


def episode_run(episode: Episode, path: str | Path, context_len: int,
                horizon_s: float) -> LoggedRun:
    """`read_logged_run` of the log `episode` was just written to (`path`), from memory."""
    return convert_run(EpisodeLog(episode, path), Path(path), context_len, horizon_s)


def frames_of(run: RunSource, path: Path) -> LoggedRun:
    """A run's frames and their features as ingest stores them (in no part yet), without
    windows: what ingest needs of a log (`evoeye.store.reading`)."""
    meta = dict(run.metadata)
    frames = frames_table(run, str(meta["scenario_id"]), UNCOMMITTED)
    return LoggedRun(path, meta, frames, frame_features(frames, FEATURES), None)


def convert_run(run: RunSource, path: Path, context_len: int, horizon_s: float) -> LoggedRun:
    """A run's conversion from its log's contents (`read_logged_run`)."""
    base = frames_of(run, path)
    meta, frames, features = base.metadata, base.frames, base.features
    sid = str(meta["scenario_id"])
    t_s = frames.column("t_s").to_numpy()
    collided = frames.column("gt_ego_collision").to_numpy(zero_copy_only=False)
    keep = eligible_frames(t_s, collided)
    labels = frame_labels(t_s, collided, horizon_s)[keep]
    rows = np.flatnonzero(keep)
    n = len(rows)
    if n == 0:
        return base
    ctx, mask = context_rows(np.zeros(n, np.int64), context_len)  # one run, from row 0
    xy = np.stack([frames.column(c).to_numpy(zero_copy_only=False)[rows].astype(np.float64)
                   for c in ("loc_x_m", "loc_y_m")], axis=1)  # (N, 2)
    eligible = FrameFeatures.empty(n, FEATURES)
    eligible.fill(0, features, rows)
    windows = Windows(
        eligible, ctx, mask, labels, np.full(n, sid, dtype=object),
        frames.column("frame").to_numpy()[rows].astype(np.int32), t_s[keep], horizon_s,
        FEATURES, xy,
    )
    return LoggedRun(path, meta, frames, features, windows)
