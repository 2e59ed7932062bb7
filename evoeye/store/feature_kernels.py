"""The frame-feature arithmetic, compiled: runtime signals of N frames → monitor inputs in place.

`evoeye.store.features.frame_features` reads the signals and calls these kernels; they are the
one definition of the features, for N frames at ingest and for one frame at run time, where a
frame costs a handful of calls instead of a few hundred numpy calls on arrays of a few items.
Every kernel loops over frames and writes the frame's rows of the `FrameFeatures` arrays it is
given (zeros where nothing is written). Arguments, per frame f of N:

    ego      (x_m, y_m, heading_rad, speed_mps): (N,) float64 each, the ADS's localization
    offsets  (N+1,) int64: items offsets[f] … offsets[f+1]-1 of a list column are frame f's

The arithmetic is IEEE double, operation for operation as numpy would do it (no fast-math, no
fused multiply-add; cos, sin and hypot from libm as numpy's), then rounded to float32, so the
features are the same bits whichever way they are computed. Compiled on first use and cached
on disk (numba, `cache=True`).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _pose(ego, f):
    """Frame f's ego pose: (x_m, y_m, heading_rad, cos, sin, vx_mps, vy_mps), map frame."""
    x_m, y_m, heading_rad, speed_mps = ego
    h = heading_rad[f]
    c, s = np.cos(h), np.sin(h)
    v = speed_mps[f]
    return x_m[f], y_m[f], h, c, s, v * c, v * s


@njit(cache=True)
def _rotate(c, s, wx, wy):
    """A world vector (wx, wy) → ego frame (forward, left), the ego heading having cos c, sin s."""
    return c * wx + s * wy, -s * wx + c * wy


@njit(cache=True)
def _finite(v):
    """v, or 0 if it is not finite."""
    return v if np.isfinite(v) else 0.0


@njit(cache=True)
def _nearest_first(dist):
    """Positions of `dist` nearest first; ties keep their order, NaN last (a stable sort)."""
    return np.argsort(dist, kind="mergesort")


@njit(cache=True)
def perception(ego, offsets, columns, out, mask):
    """The n nearest obstacles of each frame into out (N, n, 9) and mask (N, n).

    columns: the obstacles' (x_m, y_m, heading_rad, vx_mps, vy_mps, length_m, width_m,
    confidence), map frame, (M,) each; out's features are PERCEPTION_FEATURES."""
    x, y, h, vx, vy, length, width, confidence = columns
    feats = np.empty((len(x), 9))
    dist = np.empty(len(x))
    for f in range(len(offsets) - 1):
        ex, ey, eh, c, s, evx, evy = _pose(ego, f)
        lo, hi = offsets[f], offsets[f + 1]
        for i in range(lo, hi):
            row = feats[i]
            row[0], row[1] = _rotate(c, s, x[i] - ex, y[i] - ey)
            dh = h[i] - eh
            row[2], row[3] = np.cos(dh), np.sin(dh)
            row[4], row[5] = _rotate(c, s, vx[i] - evx, vy[i] - evy)
            row[6], row[7], row[8] = length[i], width[i], confidence[i]
            dist[i] = np.hypot(row[0], row[1])
        order = _nearest_first(dist[lo:hi])
        for slot in range(min(mask.shape[1], hi - lo)):
            row = feats[lo + order[slot]]
            for k in range(row.shape[0]):
                out[f, slot, k] = _finite(row[k])
            mask[f, slot] = True


@njit(cache=True)
def _point(inner, j, raw, last):
    """The value index of raw point `raw` of item j (its last point past its end, clipped to
    `last`: an item without points gets a valid but meaningless index, for its caller to mask)."""
    count = inner[j + 1] - inner[j]
    return min(inner[j] + min(raw, max(count - 1, 0)), last)


@njit(cache=True)
def prediction(ego, outer, inner, x, y, track, raw_index, out, mask):
    """Each frame's n nearest predicted obstacles into out (N, n, K, 2) and mask (N, n).

    outer (N+1,): the frame's items (one per obstacle and mode, most probable mode first);
    inner (M+1,): each item's points, absolute into the (x, y) map-frame values; track (M,) the
    item's obstacle. An obstacle's slot holds its most probable mode's points `raw_index`, in
    the ego frame; obstacles are ordered by the distance of that point 0. A slot's mask says
    whether the item had points."""
    n_items = len(inner) - 1
    if n_items <= 0 or len(x) == 0:
        return
    last = len(x) - 1
    d = np.empty((n_items, len(raw_index), 2))
    dist = np.empty(n_items)
    first = np.empty(n_items, np.bool_)
    for f in range(len(outer) - 1):
        ex, ey, _, c, s, _, _ = _pose(ego, f)
        lo, hi = outer[f], outer[f + 1]
        for j in range(lo, hi):
            for k in range(len(raw_index)):
                i = _point(inner, j, raw_index[k], last)
                d[j, k, 0], d[j, k, 1] = _rotate(c, s, x[i] - ex, y[i] - ey)
            first[j] = j == lo or track[j] != track[j - 1]  # a new obstacle: its first mode
            has_points = inner[j + 1] > inner[j]
            dist[j] = np.hypot(d[j, 0, 0], d[j, 0, 1]) if has_points and first[j] else np.inf
        order = _nearest_first(dist[lo:hi])
        for slot in range(min(mask.shape[1], hi - lo)):
            j = lo + order[slot]
            if first[j]:
                for k in range(len(raw_index)):
                    out[f, slot, k, 0] = _finite(d[j, k, 0])
                    out[f, slot, k, 1] = _finite(d[j, k, 1])
                mask[f, slot] = inner[j + 1] > inner[j]


@njit(cache=True)
def plan(ego, offsets, columns, raw_index, out, mask):
    """Each frame's planned points `raw_index` into out (N, P, 7) and mask (N, P).

    columns: the plan's (x_m, y_m, heading_rad, t_rel_s, speed_mps, accel_mps2), map frame;
    out's features are PLAN_FEATURES. A plan shorter than asked repeats its last point (masked);
    a frame without a plan keeps zeros."""
    x, y, h, t_rel, speed, accel = columns
    if len(x) == 0:
        return
    last = len(x) - 1
    for f in range(len(offsets) - 1):
        count = offsets[f + 1] - offsets[f]
        for p in range(len(raw_index)):
            mask[f, p] = raw_index[p] < count
        if count == 0:
            continue
        ex, ey, eh, c, s, _, _ = _pose(ego, f)
        for p in range(len(raw_index)):
            i = _point(offsets, f, raw_index[p], last)
            row = out[f, p]
            dx, dy = _rotate(c, s, x[i] - ex, y[i] - ey)
            dh = h[i] - eh
            row[0], row[1], row[2] = _finite(t_rel[i]), _finite(dx), _finite(dy)
            row[3], row[4] = _finite(np.cos(dh)), _finite(np.sin(dh))
            row[5], row[6] = _finite(speed[i]), _finite(accel[i])


@njit(cache=True)
def plan_info_and_control(decision, target_speed_mps, control, info_out, control_out):
    """Each frame's plan info into info_out (N, 6) and its control into control_out (N, C).

    decision (N,): the decision's position in PLANNING_DECISIONS, -1 for none known (no hot
    entry); control (C, N): the sources of CONTROL_FEATURES in order."""
    for f in range(len(decision)):
        info_out[f, 0] = _finite(target_speed_mps[f])
        if decision[f] >= 0:
            info_out[f, 1 + decision[f]] = 1.0
        for col in range(control.shape[0]):
            control_out[f, col] = _finite(control[col, f])
