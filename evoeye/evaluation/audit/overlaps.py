"""Pass-through: two NPCs whose footprints overlap for a while without a recorded contact.

A simulated contact sets `crashed` for both actors, so an overlap is pass-through on the frames
where the two are not both `crashed`. A pair counts once such frames last `min_duration_s`
(consecutive frames × frame period).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evoeye.boxes import box_corners, box_gaps
from evoeye.evaluation.audit.tracks import Tracks

MIN_OVERLAP_S = 0.2


@dataclass(frozen=True)
class PassThrough:
    """The longest stretch two NPCs overlapped without both being `crashed`."""

    actor_a: int
    actor_b: int
    start_t_s: float
    duration_s: float

    def to_dict(self) -> dict[str, float | int]:
        return {"actor_a": self.actor_a, "actor_b": self.actor_b, "start_t_s": self.start_t_s,
                "duration_s": self.duration_s}


def longest_true_run(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(length, start) of the longest run of consecutive True per column of a (T, P) mask."""
    n_frames, n_cols = mask.shape
    padded = np.zeros((n_frames + 2, n_cols), np.int8)
    padded[1:-1] = mask
    edges = np.diff(padded, axis=0)  # (T+1, P): +1 where a run starts, −1 after it ends
    length = np.zeros(n_cols, np.int64)
    start = np.zeros(n_cols, np.int64)
    for col in np.flatnonzero(mask.any(axis=0)):
        starts = np.flatnonzero(edges[:, col] == 1)
        ends = np.flatnonzero(edges[:, col] == -1)
        best = int(np.argmax(ends - starts))
        length[col], start[col] = ends[best] - starts[best], starts[best]
    return length, start


def overlap_mask(tracks: Tracks, cols_a: np.ndarray, cols_b: np.ndarray) -> np.ndarray:
    """(T, P) footprints of actor columns cols_a[p] and cols_b[p] overlap (False where absent)."""
    both = tracks.present[:, cols_a] & tracks.present[:, cols_b]  # (T, P)
    diag = np.hypot(tracks.length_m, tracks.width_m)  # (T, A)
    reach = 0.5 * (diag[:, cols_a] + diag[:, cols_b])
    centre = np.hypot(tracks.x_m[:, cols_a] - tracks.x_m[:, cols_b],
                      tracks.y_m[:, cols_a] - tracks.y_m[:, cols_b])
    near = both & (centre < reach)  # bounding circles meet: the only pairs worth a polygon test
    rows, pairs = np.nonzero(near)
    out = np.zeros(both.shape, bool)
    if len(rows):
        def corners(cols: np.ndarray) -> np.ndarray:  # (n, 4, 2)
            c = cols[pairs]
            return box_corners(tracks.x_m[rows, c], tracks.y_m[rows, c],
                               tracks.heading_rad[rows, c], tracks.length_m[rows, c],
                               tracks.width_m[rows, c])

        out[rows, pairs] = box_gaps(corners(cols_a), corners(cols_b)) <= 0.0
    return out


def check_overlaps(tracks: Tracks, rate_hz: float,
                   min_duration_s: float = MIN_OVERLAP_S) -> tuple[PassThrough, ...]:
    """Every NPC pair that overlaps without a recorded contact for ≥ min_duration_s."""
    npc = tracks.npc_columns()
    if len(npc) < 2:
        return ()
    ia, ib = np.triu_indices(len(npc), k=1)
    cols_a, cols_b = npc[ia], npc[ib]
    contact = tracks.crashed[:, cols_a] & tracks.crashed[:, cols_b]
    length, start = longest_true_run(overlap_mask(tracks, cols_a, cols_b) & ~contact)
    min_frames = int(np.ceil(min_duration_s * rate_hz - 1e-6))
    return tuple(
        PassThrough(int(tracks.actor_id[cols_a[p]]), int(tracks.actor_id[cols_b[p]]),
                    float(tracks.t_s[start[p]]), float(length[p] / rate_hz))
        for p in np.flatnonzero(length >= max(1, min_frames))
    )
