"""Feedback f_r(x) of runs under a monitor: from a fresh run log, or from the warehouse.

A new record is scored straight from its MCAP log, through the warehouse's own conversion
(`frames_table` → `frame_features`, eligible frames, contexts and labels as `eligible_frames`,
`windows.sql` and `frame_labels_h` build them), so it needs no ingest and gives the scores its
warehouse windows would get: no frame at or after the run's collision enters its feedback.
Reading the log (not the in-memory Episode) makes a freshly simulated run and one found on disk
by a resumed campaign go through exactly the same code, so their feedback is bit-identical.
Runs already ingested (the refresh after a monitor update) are scored from the warehouse.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from evoeye.evolve.feedback import ScenarioFeedback, prior_corrected, scenario_feedback
from evoeye.log import read_run
from evoeye.store.features import FEATURES, frame_features
from evoeye.store.records import frames_table
from evoeye.store.windows import Windows, load_windows

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


def run_contexts(n_frames: int, context_len: int) -> tuple[np.ndarray, np.ndarray]:
    """(ctx_row, ctx_mask), both (N, L): frame t−L+1+k clamped to 0, masked where clamped."""
    k = np.arange(n_frames)[:, None] - context_len + 1 + np.arange(context_len)[None, :]
    return np.maximum(k, 0).astype(np.int64), k >= 0


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
    ctx, mask = run_contexts(n, context_len)
    xy = np.stack([frames.column(c).to_numpy(zero_copy_only=False).astype(np.float64)
                   for c in ("loc_x_m", "loc_y_m")], axis=1)  # (N, 2)
    windows = Windows(
        frame_features(frames, FEATURES), ctx, mask, labels, np.full(n, sid, dtype=object),
        frames.column("frame").to_numpy().astype(np.int32), t_s, horizon_s, FEATURES, xy,
    )
    return LoggedRun(Path(path), meta, windows)


FEEDBACK_MODES = ("raw", "prior-corrected")  # ŷ as the monitor scores it, or σ(logit − log w)


def windows_feedback(monitor, windows: Windows, mode: str = "raw") -> ScenarioFeedback:
    """f_r per run of `windows` under `monitor` (anything with `.score(windows)`); with
    "prior-corrected", ŷ first undoes the monitor's training pos_weight (card, default 1)."""
    if mode not in FEEDBACK_MODES:
        raise ValueError(f"feedback mode must be one of {FEEDBACK_MODES}, got {mode!r}")
    scores = monitor.score(windows)
    if mode == "prior-corrected":
        card = getattr(monitor, "card", None) or {}
        scores = prior_corrected(scores, card.get("hyperparameters", {}).get("pos_weight") or 1.0)
    return scenario_feedback(scores, windows.label, windows.scenario_id)


def warehouse_feedback(root, monitor, scenario_ids, horizon_s: float,
                       mode: str = "raw") -> ScenarioFeedback:
    """f_r of ingested runs, scored from their warehouse windows (the refresh of line 13)."""
    windows = load_windows(root, list(scenario_ids), context_len=monitor.context_len,
                           horizon_s=horizon_s)
    return windows_feedback(monitor, windows, mode)
