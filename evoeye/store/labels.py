"""Eligible frames and labels in numpy: the twin of warehouse/views/05_frame_labels.sql.

The views define them for everything answered in SQL; `load_windows` and `read_logged_run`
decide them here, with the same double arithmetic, so both give the same frames and labels
(tests/store/test_labels.py compares them on a warehouse, frame by frame). Rows come grouped
by run: `run_start` holds the first row of each run (None: the rows are one run).
"""

from __future__ import annotations

import numpy as np

LABEL_EPS_S = 1e-6  # as the views: frame times sit on a float 20 Hz grid


def collision_lead_s(t_s: np.ndarray, collided: np.ndarray,
                     run_start: np.ndarray | None = None) -> np.ndarray:
    """(N,) tau_col − t per row, tau_col the earliest collided frame time of the row's run
    (min(t_s) FILTER (WHERE gt_ego_collision)); +inf in a run without a collision."""
    if len(t_s) == 0:
        return np.zeros(0)
    starts = np.zeros(1, np.int64) if run_start is None else np.asarray(run_start)
    tau = np.minimum.reduceat(np.where(collided, t_s, np.inf), starts)
    return np.repeat(tau, np.diff(np.append(starts, len(t_s)))) - t_s


def eligible_frames(t_s: np.ndarray, collided: np.ndarray,
                    run_start: np.ndarray | None = None) -> np.ndarray:
    """(N,) bool, as the view eligible_frames: the frames strictly before their run's first
    collision (every frame of a run without one)."""
    return collision_lead_s(t_s, collided, run_start) > LABEL_EPS_S


def frame_labels(t_s: np.ndarray, collided: np.ndarray, horizon_s: float,
                 run_start: np.ndarray | None = None) -> np.ndarray:
    """(N,) int8 y_t (Definition 1, as frame_labels_h): 1 iff 0 < tau_col − t ≤ H."""
    lead = collision_lead_s(t_s, collided, run_start)
    return ((lead > LABEL_EPS_S) & (lead <= horizon_s + LABEL_EPS_S)).astype(np.int8)
