"""Oriented rectangles (vehicle footprints): corners, the gap between two, and when two moving
ones first touch.

Pure numpy, shared by every layer that needs footprints: the simulator's contacts and distances
(`evoeye.sim.footprint`), the realism audit, and the TTC-2D baseline, which sees only the ADS's
perceived boxes. A rectangle is its (4, 2) corners, counter-clockwise; two rectangles overlap or
touch exactly when no edge direction of either separates them (the separating-axis test).
"""

from __future__ import annotations

import numpy as np

# beyond the two half widths: the lateral corridor an actor ahead is "in" (TTC baselines,
# criticality, collision mechanisms)
CORRIDOR_MARGIN_M = 0.3
_UNIT = np.array([[0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.5, -0.5]])  # corners, box frame


def box_corners(x: np.ndarray, y: np.ndarray, heading: np.ndarray, length: np.ndarray,
                width: np.ndarray) -> np.ndarray:
    """(N, 4, 2) corners of N oriented rectangles, counter-clockwise."""
    local = _UNIT[None] * np.stack([length, width], axis=-1)[:, None, :]  # (N, 4, 2)
    c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
    return np.stack([x[:, None] + c * local[..., 0] - s * local[..., 1],
                     y[:, None] + s * local[..., 0] + c * local[..., 1]], axis=-1)


def box_gap_bound(x: np.ndarray, y: np.ndarray, h: np.ndarray, length: np.ndarray,
                  width: np.ndarray, ox: np.ndarray, oy: np.ndarray, oh: np.ndarray,
                  olength: np.ndarray, owidth: np.ndarray) -> np.ndarray:
    """Distance from box (x, y, h, length, width) to the bounding box, in its own frame, of the
    box o: a lower bound of their `box_gaps`, exact unless the closest points of the two are
    corner to corner (the bounding box along an axis reaches exactly o's extreme corner), for a
    dozen elementwise operations instead of the exact gap's corner-to-edge pairs."""
    c, s = np.cos(h), np.sin(h)
    dx, dy = ox - x, oy - y
    ca, sa = np.abs(np.cos(oh - h)), np.abs(np.sin(oh - h))
    gap_x = np.abs(c * dx + s * dy) - 0.5 * (length + olength * ca + owidth * sa)
    gap_y = np.abs(c * dy - s * dx) - 0.5 * (width + olength * sa + owidth * ca)
    return np.hypot(np.maximum(gap_x, 0.0), np.maximum(gap_y, 0.0))


def _axes(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 4, 2) the separating-axis candidates of rectangles a and b: two edges of each."""
    return np.concatenate([a[..., 1:3, :] - a[..., 0:2, :], b[..., 1:3, :] - b[..., 0:2, :]],
                          axis=-2)


def _extent(corners: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) over the corners of their projections on each axis, both (..., 4)."""
    proj = corners @ np.swapaxes(axes, -1, -2)  # (..., corner, axis)
    return proj.min(axis=-2), proj.max(axis=-2)


def box_gaps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,) Euclidean distance between rectangles a[i] and b[i] ((N, 4, 2) corners); 0 if they
    overlap. Separated: the smallest corner-to-edge distance, both ways in one pass (for convex
    polygons that do not overlap, the closest pair always involves a corner)."""
    n = len(a)
    p, q = np.concatenate([a, b]), np.concatenate([b, a])  # corners of p to edges of q
    ab = np.roll(q, -1, axis=1) - q  # edges q_m → q_{m+1}
    ap = p[:, :, None, :] - q[:, None, :, :]  # (2N, corner, edge, 2)
    t = np.einsum("nkmd,nmd->nkm", ap, ab) / np.einsum("nmd,nmd->nm", ab, ab)[:, None, :]
    d = ap - np.clip(t, 0.0, 1.0)[..., None] * ab[:, None]
    dist = np.sqrt(np.einsum("nkmd,nkmd->nkm", d, d).reshape(2 * n, -1).min(axis=1))
    axes = _axes(a, b)
    a_lo, a_hi = _extent(a, axes)
    b_lo, b_hi = _extent(b, axes)
    separated = ((a_hi < b_lo) | (b_hi < a_lo)).any(axis=1)
    return np.where(separated, np.minimum(dist[:n], dist[n:]), 0.0)


def first_contact_s(a: np.ndarray, b: np.ndarray, velocity_mps: np.ndarray) -> np.ndarray:
    """(...) the earliest time t ≥ 0 (s) at which rectangle b, translating at `velocity_mps`
    (..., 2) relative to rectangle a, overlaps or touches it, both keeping their headings; 0 if
    they overlap now, +inf if never. a, b: (..., 4, 2) corners.

    Exact, with no time steps: on each separating axis the projections overlap during one
    interval of t (all t, or none, when b does not move along the axis); the rectangles overlap
    while every axis does, so contact begins at the latest interval start, if that comes before
    the earliest interval end.
    """
    axes = _axes(a, b)
    a_lo, a_hi = _extent(a, axes)
    b_lo, b_hi = _extent(b, axes)
    speed = np.einsum("...d,...md->...m", velocity_mps, axes)  # (..., 4) along each axis
    moving = speed != 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (a_lo - b_hi) / speed, (a_hi - b_lo) / speed  # b's span meets a's ends
    overlap_now = (b_lo <= a_hi) & (b_hi >= a_lo)
    start = np.where(moving, np.minimum(t1, t2), np.where(overlap_now, -np.inf, np.inf))
    end = np.where(moving, np.maximum(t1, t2), np.where(overlap_now, np.inf, -np.inf))
    t = np.maximum(start.max(axis=-1), 0.0)
    return np.where(t <= end.min(axis=-1), t, np.inf)
