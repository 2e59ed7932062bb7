"""A run's ground truth as (frames, actors) arrays, read from its log's `/sim/ground_truth` only.

The audit never needs the ADS channels: it reads the ground-truth messages, the `evoeye.run`
record and the road map, and lays every actor on one grid (NaN / False where it is absent).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from itertools import chain
from typing import Any

import numpy as np

from evoeye.log.channels import TOPICS
from evoeye.log.reader import read_run
from evoeye.scene import EGO_ID

_FLOAT_FIELDS = ("x_m", "y_m", "heading_rad", "vx_mps", "vy_mps", "length_m", "width_m")


@dataclass(frozen=True)
class Tracks:
    """Every actor of a run on a (T frames, A actors) grid, the ego in column 0."""

    t_s: np.ndarray  # (T,)
    actor_id: np.ndarray  # (A,) int64, EGO_ID first
    present: np.ndarray  # (T, A) bool
    x_m: np.ndarray  # (T, A) NaN where absent; likewise every float field below
    y_m: np.ndarray
    heading_rad: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray
    length_m: np.ndarray
    width_m: np.ndarray
    crashed: np.ndarray  # (T, A) bool, False where absent
    ego_collision: np.ndarray  # (T,) bool

    @property
    def ego_collision_time_s(self) -> float | None:
        """Time of the first frame with the ego in a collision; None if it never collides."""
        hit = np.flatnonzero(self.ego_collision)
        return float(self.t_s[hit[0]]) if len(hit) else None

    def before_ego_collision(self) -> np.ndarray:
        """(T,) frames strictly before the ego's first collision (all frames if none)."""
        t_col = self.ego_collision_time_s
        return np.ones(len(self.t_s), bool) if t_col is None else self.t_s < t_col

    def npc_columns(self) -> np.ndarray:
        """Column indices of every actor but the ego."""
        return np.flatnonzero(self.actor_id != EGO_ID)


def tracks_from_messages(messages: list[dict[str, Any]]) -> Tracks:
    """Ground-truth message dicts (schemas/mcap/ground_truth.v1.json), in time order → Tracks."""
    n_frames = len(messages)
    counts = np.fromiter((len(m["actor_id"]) for m in messages), np.int64, n_frames)
    ids = np.fromiter(chain.from_iterable(m["actor_id"] for m in messages), np.int64,
                      int(counts.sum()))
    actor_id, col = np.unique(ids, return_inverse=True)  # EGO_ID = 0 sorts first
    row = np.repeat(np.arange(n_frames), counts)
    present = np.zeros((n_frames, len(actor_id)), bool)
    present[row, col] = True

    def grid(name: str) -> np.ndarray:
        flat = np.fromiter(chain.from_iterable(m[name] for m in messages), np.float64, len(ids))
        out = np.full(present.shape, np.nan)
        out[row, col] = flat
        return out

    crashed = np.zeros(present.shape, bool)
    crashed[row, col] = np.fromiter(chain.from_iterable(m["crashed"] for m in messages), bool,
                                    len(ids))
    return Tracks(
        t_s=np.fromiter((m["t_s"] for m in messages), np.float64, n_frames),
        actor_id=actor_id, present=present, **{f: grid(f) for f in _FLOAT_FIELDS},
        crashed=crashed,
        ego_collision=np.fromiter((m["ego_collision"] for m in messages), bool, n_frames),
    )


@dataclass(frozen=True)
class RunGroundTruth:
    """What the audit reads of one log: the run record, the map's lanes and the tracks."""

    path: str
    metadata: dict[str, Any]  # schemas/mcap/run.v1.json
    lanes: tuple[np.ndarray, ...]  # (K, 2) lane centre lines
    tracks: Tracks


def read_ground_truth(path: str | os.PathLike) -> RunGroundTruth:
    """Read only the ground-truth channel, the run record and the road map of a log."""
    log = read_run(path, topics=[TOPICS.ground_truth])
    messages = [m for _, m in log.messages(TOPICS.ground_truth)]
    lanes = tuple(lane.points for lane in log.road_map.lanes) if log.road_map else ()
    return RunGroundTruth(str(path), log.metadata, lanes, tracks_from_messages(messages))
