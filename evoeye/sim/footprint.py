"""Distances between vehicle footprints: oriented rectangles of length × width about their centre.

The outcome's `min_distance_m` (and AV-Fuzzer's fitness, which is built on it) needs the true
gap between the ego's footprint and another vehicle's: 0 only when the two rectangles touch or
overlap. Centre distance minus half-lengths is not that gap — two cars side by side in adjacent
lanes (4 m apart, 5 m long) would be at "distance 0" — so this computes the Euclidean distance
between the rectangles: 0 if a separating-axis test finds them overlapping, otherwise the
smallest corner-to-edge distance either way (for convex polygons that do not overlap, the
closest pair always involves a corner). Vectorised over the other actors.
"""

from __future__ import annotations

import numpy as np

from evoeye.scene import SceneState

_UNIT = np.array([[0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.5, -0.5]])  # corners, box frame


def box_corners(x: np.ndarray, y: np.ndarray, heading: np.ndarray, length: np.ndarray,
                width: np.ndarray) -> np.ndarray:
    """(N, 4, 2) corners of N oriented rectangles, counter-clockwise."""
    local = _UNIT[None] * np.stack([length, width], axis=-1)[:, None, :]  # (N, 4, 2)
    c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
    return np.stack([x[:, None] + c * local[..., 0] - s * local[..., 1],
                     y[:, None] + s * local[..., 0] + c * local[..., 1]], axis=-1)


def _corner_to_edge(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N,) smallest distance from a corner of box p[i] (N, 4, 2) to an edge of box q[i]."""
    a, b = q, np.roll(q, -1, axis=1)  # edges a→b, (N, 4, 2)
    ab = b - a
    ap = p[:, :, None, :] - a[:, None, :, :]  # (N, corner, edge, 2)
    t = np.clip((ap * ab[:, None]).sum(-1) / (ab * ab).sum(-1)[:, None], 0.0, 1.0)
    closest = a[:, None] + t[..., None] * ab[:, None]
    return np.linalg.norm(p[:, :, None, :] - closest, axis=-1).min(axis=(1, 2))


def _overlap(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N,) bool: boxes p[i] and q[i] overlap (no separating axis among their edge normals)."""
    axes = np.concatenate([p[:, 1:3] - p[:, 0:2], q[:, 1:3] - q[:, 0:2]], axis=1)  # (N, 4, 2)
    proj_p = np.einsum("nkd,nad->nak", p, axes)  # (N, axis, corner)
    proj_q = np.einsum("nkd,nad->nak", q, axes)
    separated = (proj_p.max(-1) < proj_q.min(-1)) | (proj_q.max(-1) < proj_p.min(-1))
    return ~separated.any(axis=1)


def box_gaps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,) Euclidean distance between rectangles a[i] and b[i] ((N, 4, 2) corners); 0 if they
    overlap."""
    gap = np.minimum(_corner_to_edge(a, b), _corner_to_edge(b, a))
    return np.where(_overlap(a, b), 0.0, gap)


def ego_gaps(scene: SceneState) -> np.ndarray:
    """(N−1,) footprint distance from the ego (row 0) to every other actor."""
    corners = box_corners(scene.x_m, scene.y_m, scene.heading_rad, scene.length_m,
                          scene.width_m)
    others = corners[1:]
    return box_gaps(np.broadcast_to(corners[:1], others.shape), others)


def min_ego_gap(scene: SceneState, below: float = np.inf) -> float:
    """The smallest ego footprint distance if it is below `below`, else +inf (cheaply: actors
    whose centre distance minus both half-diagonals — a lower bound — is not below are
    skipped, which is nearly every actor of nearly every frame of a run)."""
    if scene.n < 2 or below <= 0.0:
        return np.inf
    half_diag = 0.5 * np.hypot(scene.length_m, scene.width_m)
    bound = (np.hypot(scene.x_m[1:] - scene.x_m[0], scene.y_m[1:] - scene.y_m[0])
             - half_diag[1:] - half_diag[0])
    near = np.flatnonzero(bound < below) + 1
    if not len(near):
        return np.inf
    rows = np.concatenate(([0], near))
    corners = box_corners(scene.x_m[rows], scene.y_m[rows], scene.heading_rad[rows],
                          scene.length_m[rows], scene.width_m[rows])
    gap = float(box_gaps(np.broadcast_to(corners[:1], corners[1:].shape), corners[1:]).min())
    return gap if gap < below else np.inf
