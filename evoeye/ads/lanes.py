"""The map's lane graph as prediction needs it: continuations (successors) and neighbours.

The map lists lanes without topology; a lane *continues* another when it starts within
`join_m` of the other's end, heading on. A *path* is a lane followed by one continuation (and the
continuation's own unique continuation if it is short, so a turn runs on into its exit lane);
a lane without continuations is its own path. All paths live in one `PolylineIndex`, so a point
at arc length s on lane l and path p is `paths.xy_at(paths.offset[p] + s)` for every (obstacle,
path) pair at once. `lane_paths` (L, M) lists each lane's paths, −1 padded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evoeye.ads.geometry import PolylineIndex
from evoeye.scene import Lane

SHORT_LANE_M = 60.0  # a continuation shorter than this is extended by its own continuation
NEIGHBOUR_TOLERANCE_M = 1.0  # a parallel lane within this of ±one lane width is a neighbour


@dataclass(frozen=True)
class LaneGraph:
    """Paths through the lanes and each lane's left/right neighbours."""

    paths: PolylineIndex
    lane_paths: np.ndarray  # (L, M) path ids of each lane, −1 padded
    width_m: np.ndarray  # (L,) lane width
    has_left: np.ndarray  # (L,) bool: a lane one width to the left, going the same way
    has_right: np.ndarray  # (L,) bool

    @classmethod
    def build(cls, lanes: tuple[Lane, ...], index: PolylineIndex, join_m: float,
              spacing_m: float) -> LaneGraph:
        """The graph of `lanes`; `index` is their PolylineIndex (with heading sectors)."""
        starts = np.array([ln.points[0] for ln in lanes])  # (L, 2)
        ends = np.array([ln.points[-1] for ln in lanes])
        h0 = np.array([_heading(ln.points[:2]) for ln in lanes])
        h1 = np.array([_heading(ln.points[-2:]) for ln in lanes])
        near = np.hypot(*(ends[:, None, :] - starts[None, :, :]).transpose(2, 0, 1)) <= join_m
        successors = near & (np.cos(h1[:, None] - h0[None, :]) > 0.5)  # (L, L) i → j
        np.fill_diagonal(successors, False)
        polylines, owner = [], []
        for i, lane in enumerate(lanes):
            nxt = successors[i].nonzero()[0]
            for j in nxt.tolist() or [None]:
                parts = [lane.points]
                if j is not None:
                    parts.append(lanes[j].points[1:])
                    after = successors[j].nonzero()[0]
                    if len(after) == 1 and _length(lanes[j].points) < SHORT_LANE_M:
                        parts.append(lanes[int(after[0])].points[1:])
                polylines.append(np.concatenate(parts))
                owner.append(i)
        owner_a = np.asarray(owner)
        m = int(np.bincount(owner_a, minlength=len(lanes)).max())
        table = np.full((len(lanes), m), -1, dtype=np.int64)
        for i in range(len(lanes)):
            ids = (owner_a == i).nonzero()[0]
            table[i, : len(ids)] = ids
        paths = PolylineIndex.build(polylines, spacing_m, 1.0, 4.0, 1)
        width = np.array([ln.width_m for ln in lanes])
        has_left, has_right = _neighbours(lanes, index, width)
        return cls(paths, table, width, has_left, has_right)


def _heading(two: np.ndarray) -> float:
    d = two[1] - two[0]
    return math.atan2(float(d[1]), float(d[0]))


def _length(points: np.ndarray) -> float:
    return float(np.hypot(*np.diff(points, axis=0).T).sum())


def _neighbours(
    lanes: tuple[Lane, ...], index: PolylineIndex, width_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Whether a same-direction lane lies one width to the left / right of each lane's middle."""
    mid = np.array([ln.points[len(ln.points) // 2] for ln in lanes])  # (L, 2)
    h = np.array([_heading(ln.points[len(ln.points) // 2 - 1:len(ln.points) // 2 + 1])
                  if len(ln.points) > 2 else _heading(ln.points[:2]) for ln in lanes])
    out = []
    for side in (1.0, -1.0):
        px = mid[:, 0] - side * width_m * np.sin(h)
        py = mid[:, 1] + side * width_m * np.cos(h)
        v = index.candidates(px, py, h)
        _, lat, _, _ = index.project(px, py, v)
        out.append((index.line[v] >= 0) & (index.line[v] != np.arange(len(lanes)))
                   & (np.abs(lat) <= NEIGHBOUR_TOLERANCE_M))
    return out[0], out[1]
