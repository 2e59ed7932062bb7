"""Distances between vehicle footprints: oriented rectangles of length × width about their centre.

The outcome's `min_distance_m` (and AV-Fuzzer's fitness, which is built on it) needs the true
gap between the ego's footprint and another vehicle's: 0 only when the two rectangles touch or
overlap. Centre distance minus half-lengths is not that gap — two cars side by side in adjacent
lanes (4 m apart, 5 m long) would be at "distance 0" — so this computes the Euclidean distance
between the rectangles (`evoeye.boxes.box_gaps`): 0 if a separating-axis test finds them
overlapping, otherwise the smallest corner-to-edge distance either way. Vectorised over the
other actors.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evoeye.boxes import box_corners, box_gap_bound, box_gaps
from evoeye.scene import SceneState

__all__ = ["ego_gaps", "min_ego_gap"]


def ego_gaps(scene: SceneState) -> np.ndarray:
    """(N−1,) footprint distance from the ego (row 0) to every other actor."""
    corners = box_corners(scene.x_m, scene.y_m, scene.heading_rad, scene.length_m,
                          scene.width_m)
    others = corners[1:]
    return box_gaps(np.broadcast_to(corners[:1], others.shape), others)


def min_ego_gap(scenes: Sequence[SceneState], batch: int = 16) -> float:
    """The smallest ego footprint distance over a run's scenes (+inf if the ego was alone).

    Branch and bound: a lower bound for every (frame, actor) pair at once — the larger of each
    box's distance to the other's bounding box in its own frame, exact unless the closest
    points are corner to corner — then exact distances in increasing order of the bound, a
    batch at a time, until the next bound is no smaller than the best exact distance. A run
    needs a handful of exact distances instead of one per frame."""
    scenes = [sc for sc in scenes if sc.n > 1]
    if not scenes:
        return np.inf
    rows = np.stack([np.concatenate([getattr(sc, name) for sc in scenes]) for name in (
        "x_m", "y_m", "heading_rad", "length_m", "width_m")])  # (5, actors of every scene)
    n = np.array([sc.n for sc in scenes])
    start = np.cumsum(n) - n  # each scene's ego row
    is_other = np.ones(rows.shape[1], dtype=bool)
    is_other[start] = False
    ego = rows[:, np.repeat(start, n - 1)]  # (5, pairs): x, y, heading, length, width
    other = rows[:, is_other]
    bound = np.maximum(box_gap_bound(*ego, *other), box_gap_bound(*other, *ego))
    order = np.argsort(bound, kind="stable")
    best = np.inf
    for start in range(0, len(order), batch):
        idx = order[start:start + batch]
        if bound[idx[0]] >= best:
            break
        best = min(best, float(box_gaps(box_corners(*ego[:, idx]),
                                        box_corners(*other[:, idx])).min()))
    return best
