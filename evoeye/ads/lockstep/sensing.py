"""The sensor set over a batch of runs: `SensorModel.detect` once for B runs of one scenario.

Every run keeps its own model and random stream. The draws come first, run by run in the per-run
order (uniforms, then normals, into rows of one (B, ·) array); the geometry is then computed once
on (B, n) arrays — n actors besides the ego, the same in every run of one logical scenario. The
per-run code's arithmetic is elementwise except for the pairwise parts, which keep a per-run
(B, n, n) layout so that every sum and comparison sees what it sees per run: the occlusion
overlaps (summed along the last axis, as per run), the merge pre-check and gap test, and the
static occluders (padded with NaN boxes, which never block: every comparison with NaN is false).
The ragged rest is handled on flat selections of the (B, n) arrays, whose elementwise results do
not depend on where an element sits: radar-only boxes, ghosts and clutter for all runs at once,
and the rare segment merging per run, with `merge_segments` itself, for the runs that merge.
The model's derived constants and the clutter count's CDF are read from the first model of a
group: every model of a group has the same configuration. Detections of every run go into one
pool of columns, are moved to the world frame in one pass with per-column poses, and are handed
back per run in the per-run order (actors, ghosts, clutter), as C-ordered (DET_FIELDS, m)
arrays. (Per run, `z[:, seen]` and numpy's choice of layout for a concatenation leave some
Fortran-ordered: the memory order is not reproduced, only the values; the tracker, their only
consumer, reads them elementwise, where the order makes no difference to a bit.)

A lone run goes to `SensorModel.detect` itself: with nothing to share, it is the faster way.

Scalars that the per-run code computes with `math`/`cmath` on Python floats (the pose's cos and
sin, the frame rotation, the merge reach) are computed the same way here, run by run: numpy's
versions may differ by an ulp.
"""

from __future__ import annotations

import bisect
import cmath
import math
from collections.abc import Sequence

import numpy as np

from evoeye.ads.clutter import CLUTTER_ID, CLUTTER_SIZE_M, GHOST_ID
from evoeye.ads.detections import (
    DET_FIELDS,
    DET_HEADING,
    DET_LENGTH,
    DET_RANGE,
    DET_VAR_POS,
    DET_VAR_VEL,
    DET_VX,
    DET_VY,
    DET_WIDTH,
    DET_X,
    DET_Y,
    VAR_FLOOR,
    Detections,
    pack,
)
from evoeye.ads.messages import Localization
from evoeye.ads.sensing import N_NORMALS, SensorModel, merge_segments
from evoeye.scene import SceneState


def detect_batch(
    models: Sequence[SensorModel], scenes: Sequence[SceneState],
    egos: Sequence[Localization | None],
) -> list[Detections]:
    """`[m.detect(s, e) for m, s, e in zip(models, scenes, egos)]`, bit for bit, every model's
    stream advanced as per run. Runs are grouped by sensor configuration and number of actors
    (one group in a lockstep batch of one scenario); each group is computed at once (the
    arrays of one run too, when it is a group of its own)."""
    if not len(models) == len(scenes) == len(egos):
        raise ValueError(f"need one scene and one ego per model, got {len(models)} models, "
                         f"{len(scenes)} scenes, {len(egos)} egos")
    if len(models) < 2:  # nothing to share: the per-run code is the faster way to the same
        return [m.detect(s, e) for m, s, e in zip(models, scenes, egos, strict=True)]
    c0, n0 = models[0].c, scenes[0].n
    if all(s.n == n0 and (m.c is c0 or m.c == c0) for m, s in zip(models, scenes, strict=True)):
        return _detect_group(models, scenes, egos)
    groups: dict[tuple, list[int]] = {}
    for i, (m, s) in enumerate(zip(models, scenes, strict=True)):
        groups.setdefault((m.c, s.n), []).append(i)
    # draws in the order of the runs, not of the groups: models may share a stream
    draws = [_draw([m], s.n - 1) for m, s in zip(models, scenes, strict=True)]
    out: list[Detections] = [None] * len(models)  # type: ignore[list-item]
    for idx in groups.values():
        dets = _detect_group([models[i] for i in idx], [scenes[i] for i in idx],
                             [egos[i] for i in idx],
                             (np.concatenate([draws[i][0] for i in idx]),
                              np.concatenate([draws[i][1] for i in idx])))
        for i, d in zip(idx, dets, strict=True):
            out[i] = d
    return out


def _rows(fields: list[np.ndarray]) -> np.ndarray:
    """One field of every run's scene, (B, n + 1) (`np.stack`'s result, at a fraction of its
    cost for many small arrays)."""
    return np.concatenate(fields).reshape(len(fields), -1)


def _draw(models: Sequence[SensorModel], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Each model's uniforms (B, 3n + clutter) and normals (B, N_NORMALS·n), drawn from its
    stream in the per-run order (`out=` fills a row with what `size=` would return)."""
    u = np.empty((len(models), 3 * n + models[0].false_positives.n_uniforms))
    g = np.empty((len(models), N_NORMALS * n))
    for m, u_b, g_b in zip(models, u, g, strict=True):
        m.rng.random(out=u_b)
        m.rng.standard_normal(out=g_b)
    return u, g


def _occluded_fraction(range_m: np.ndarray, bearing_rad: np.ndarray,
                       half_width_rad: np.ndarray) -> np.ndarray:
    """`sensing.occluded_fraction` per run of (B, n) arrays: the (B, n, n) overlaps are summed
    along the last axis, each row as the per-run (n, n) reduction sums it."""
    lo = bearing_rad - half_width_rad
    hi = bearing_rad + half_width_rad
    overlap = np.minimum(hi[:, :, None], hi[:, None, :]) - np.maximum(lo[:, :, None],
                                                                       lo[:, None, :])
    overlap = np.where(range_m[:, :, None] > range_m[:, None, :], overlap, 0.0)
    return np.minimum(np.add.reduce(np.maximum(overlap, 0.0), axis=2) / (hi - lo), 1.0)


def _line_of_sight_blocked(x0: np.ndarray, y0: np.ndarray, x: np.ndarray, y: np.ndarray,
                           scenes: Sequence[SceneState]) -> np.ndarray | None:
    """`sensing.line_of_sight_blocked` per run: (B, n) from the ego (x0, y0) (B, 1) to (x, y)
    (B, n) against each scene's occluders, padded to one (B, K, 4) with NaN boxes; None if no
    scene has any."""
    k = max(0 if s.occluders is None else len(s.occluders) for s in scenes)
    if k == 0:
        return None
    boxes = np.full((len(scenes), k, 4), np.nan)
    for b, s in enumerate(scenes):
        if s.occluders is not None:
            boxes[b, :len(s.occluders)] = s.occluders
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_dx, inv_dy = (1.0 / (x - x0))[:, :, None], (1.0 / (y - y0))[:, :, None]
        x0, y0 = x0[:, :, None], y0[:, :, None]
        tx1 = (boxes[:, None, :, 0] - x0) * inv_dx  # (B, n, K)
        tx2 = (boxes[:, None, :, 2] - x0) * inv_dx
        ty1 = (boxes[:, None, :, 1] - y0) * inv_dy
        ty2 = (boxes[:, None, :, 3] - y0) * inv_dy
        t_in = np.maximum(np.fmin(tx1, tx2), np.fmin(ty1, ty2))
        t_out = np.minimum(np.fmax(tx1, tx2), np.fmax(ty1, ty2))
        return ((t_out >= np.maximum(t_in, 0.0)) & (t_in <= 1.0)).any(axis=2)


def _may_merge(c, pos: np.ndarray, lidar: np.ndarray, length_m: np.ndarray,
               width_m: np.ndarray) -> np.ndarray:
    """`SensorModel._may_merge` and its guard per run: (B,) whether a run has two lidar
    detections whose centres are within reach of each other."""
    g = c.lidar_merge_gap_m
    reach = np.array([math.hypot(a + g, w + g) for a, w in zip(
        length_m.max(axis=1).tolist(), width_m.max(axis=1).tolist(), strict=True)])
    d = np.abs(pos[:, :, None] - pos[:, None, :])  # (B, n, n)
    near = (d < reach[:, None, None]) & lidar[:, :, None] & lidar[:, None, :]
    m = np.count_nonzero(lidar, axis=1)
    return (m > 1) & (np.count_nonzero(near, axis=(1, 2)) > m)


def _merge(c, lidar: np.ndarray, pos_l: np.ndarray, vel_l: np.ndarray, len_l: np.ndarray,
           wid_l: np.ndarray, h_rel: np.ndarray, length_m: np.ndarray, width_m: np.ndarray,
           range_m: np.ndarray) -> None:
    """The lidar segmentation of `SensorModel.detect` per run of (B, n) arrays, in place.

    A run that passes the pre-check gets what `merge_segments` returns for its lidar
    detections. Where no two are within the gap, that is their positions and velocities as they
    are and, as boxes, the true lengths and widths (not the visible ones): set here for all such
    runs at once. Whether two are within the gap is `merge_segments`' own test, elementwise on
    (B', n, n); only the rare runs where they are call `merge_segments` itself.
    """
    may = _may_merge(c, pos_l, lidar, length_m, width_m)
    if not np.count_nonzero(may):
        return
    boxes = may[:, None] & lidar
    len_l[boxes], wid_l[boxes] = length_m[boxes], width_m[boxes]
    rows = may.nonzero()[0]
    pos, seen, r = pos_l[rows], lidar[rows], range_m[rows]
    length, width = length_m[rows], width_m[rows]
    rel = (pos[:, None, :] - pos[:, :, None]) * np.exp(-1j * h_rel[rows])[:, :, None]
    gap = np.maximum(np.abs(rel.real) - 0.5 * (length[:, :, None] + length[:, None, :]),
                     np.abs(rel.imag) - 0.5 * (width[:, :, None] + width[:, None, :]))
    absorbs = (gap < c.lidar_merge_gap_m) & (r[:, :, None] < r[:, None, :]) & (
        seen[:, :, None] & seen[:, None, :])  # [b, i, j]: i absorbs the farther j
    for b in rows[absorbs.any(axis=(1, 2))].tolist():
        i = lidar[b].nonzero()[0]
        keep, pos_l[b, i], vel_l[b, i], len_l[b, i], wid_l[b, i] = merge_segments(
            pos_l[b, i], vel_l[b, i], h_rel[b, i], length_m[b, i], width_m[b, i], range_m[b, i],
            c.lidar_merge_gap_m)
        lidar[b, i[~keep]] = False


def _clutter(fp, u: np.ndarray, v0: list[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`FalsePositives.detect` for every run at once, from each run's clutter uniforms u
    (B, n_uniforms) and true ego speed: (runs, ids, (DET_FIELDS, k) detections), run-major."""
    c, n_max = fp.c, fp.n_max
    k = np.array([bisect.bisect_right(fp._cdf, u_b) for u_b in u[:, 0].tolist()], dtype=np.int64)
    if not k.any():
        return np.zeros(0, dtype=np.int64), fp._none[0], fp._none[1]
    slots = np.arange(n_max) < k[:, None]  # (B, n_max): row-major = the per-run order
    r = c.clutter_min_range_m + (c.lidar_range_m - c.clutter_min_range_m) * u[:, 1:1 + n_max][
        slots]
    bearing = (2.0 * u[:, 1 + n_max:1 + 2 * n_max][slots] - 1.0) * math.pi
    runs = np.repeat(np.arange(len(k)), k)
    vel = np.array([-v + 0j for v in v0]).take(runs)  # static in the world
    z = pack(r * np.exp(1j * bearing), vel, 0.0, CLUTTER_SIZE_M, CLUTTER_SIZE_M, r,
             (c.pos_sigma_m + c.pos_sigma_per_m * r) ** 2 + VAR_FLOOR,
             (c.vel_sigma_mps + c.vel_sigma_per_m * r) ** 2 + VAR_FLOOR)
    return runs, np.full(len(runs), CLUTTER_ID, dtype=np.int64), z


def _actors(models: Sequence[SensorModel], scenes: Sequence[SceneState], u: np.ndarray,
            g: np.ndarray, x: np.ndarray, y: np.ndarray, h: np.ndarray, v: np.ndarray,
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The actor part of `SensorModel.detect` for (B, n + 1) ground truth: the sensor-frame
    detections (DET_FIELDS, B, n), which actors are seen and which have a multipath ghost
    drawn (B, n)."""
    m0 = models[0]
    c = m0.c
    n = x.shape[1] - 1
    x0, y0, h0, v0 = x[:, :1], y[:, :1], h[:, :1], v[:, :1]
    rot = np.array([cmath.exp(-1j * a) for a in h[:, 0].tolist()])[:, None]
    rel = ((x[:, 1:] - x0) + 1j * (y[:, 1:] - y0)) * rot  # (B, n)
    h_rel = h[:, 1:] - h0
    e_h = np.exp(1j * h_rel)
    vrel = v[:, 1:] * e_h - v0
    r = np.abs(rel)
    bearing = np.arctan2(rel.imag, rel.real)
    los = rel / r
    e_phi = e_h / los
    cos_phi, sin_phi = np.abs(e_phi.real), np.abs(e_phi.imag)
    length = _rows([s.length_m for s in scenes])[:, 1:]
    width = _rows([s.width_m for s in scenes])[:, 1:]
    occ = _occluded_fraction(r, bearing, np.arctan2(length * sin_phi + width * cos_phi, r + r))
    blocked = _line_of_sight_blocked(x0, y0, x[:, 1:], y[:, 1:], scenes)
    if blocked is not None:
        occ = np.where(blocked, 1.0, occ)
    lidar, radar = m0.seen_by(u, n, r, occ, bearing)
    pos_l, vel_l, head_l, len_l, wid_l, var_pl, var_vl = m0.lidar_boxes(
        g, n, rel, los, vrel, h_rel, r, length, width, cos_phi, sin_phi)
    if n > 1:
        _merge(c, lidar, pos_l, vel_l, len_l, wid_l, h_rel, length, width, r)

    rm, los_r, rr, pos_l, vel_l = m0.radar_fusion(
        g, n, r, bearing, vrel, los, lidar & radar, pos_l, vel_l, var_pl, var_vl)
    z = np.empty((DET_FIELDS,) + r.shape)
    z[DET_X], z[DET_Y] = pos_l.real, pos_l.imag
    z[DET_VX], z[DET_VY] = vel_l.real, vel_l.imag
    z[DET_HEADING], z[DET_LENGTH], z[DET_WIDTH], z[DET_RANGE] = head_l, len_l, wid_l, r
    z[DET_VAR_POS], z[DET_VAR_VEL] = var_pl, var_vl
    radar_only = radar & ~lidar
    if np.count_nonzero(radar_only):
        los_j = los_r[radar_only]
        pos_r, vel_r = rm[radar_only] * los_j, rr[radar_only] * los_j
        vel_abs = vel_r + np.broadcast_to(v0, r.shape)[radar_only]
        head_r = np.where(np.abs(vel_abs) > 1.0, np.arctan2(vel_abs.imag, vel_abs.real), 0.0)
        var_pr = np.maximum(m0._var_range, (r[radar_only] * c.radar_azimuth_sigma_rad) ** 2
                            + VAR_FLOOR)
        z[:, radar_only] = pack(pos_r, vel_r, head_r, c.radar_length_m, c.radar_width_m,
                                r[radar_only], var_pr, m0._radar_var_vel)
    multipath = radar & (u[:, 2 * n:3 * n] < c.ghost_prob) & (r > c.ghost_min_range_m)
    return z, lidar | radar, multipath


def _to_world(z: np.ndarray, runs: np.ndarray, poses: np.ndarray) -> None:
    """`sensing.to_world` in place for columns of several runs: poses (6, B) rows x, y, cos,
    sin, speed, heading (cos and sin from `math`, as per run), taken per column by run."""
    x0, y0, c, s, v0, h0 = poses.take(runs, axis=1)
    px, py = z[DET_X].copy(), z[DET_Y].copy()
    z[DET_X] = x0 + c * px - s * py
    z[DET_Y] = y0 + s * px + c * py
    vx, vy = z[DET_VX] + v0, z[DET_VY].copy()
    z[DET_VX] = c * vx - s * vy
    z[DET_VY] = s * vx + c * vy
    z[DET_HEADING] += h0


def _detect_group(models: Sequence[SensorModel], scenes: Sequence[SceneState],
                  egos: Sequence[Localization | None],
                  draws: tuple[np.ndarray, np.ndarray] | None = None) -> list[Detections]:
    """`detect_batch` for runs sharing one sensor configuration and number of actors; `draws`:
    their (u, g) if already drawn."""
    n_runs, n = len(models), scenes[0].n - 1
    u, g = draws or _draw(models, n)
    x = _rows([s.x_m for s in scenes])  # (B, n + 1), column 0 the ego
    y = _rows([s.y_m for s in scenes])
    h = _rows([s.heading_rad for s in scenes])
    v = _rows([s.speed_mps for s in scenes])
    pose = [(x_b, y_b, h_b, v_b) if e is None else (e.x_m, e.y_m, e.heading_rad, e.speed_mps)
            for x_b, y_b, h_b, v_b, e in zip(x[:, 0].tolist(), y[:, 0].tolist(),
                                             h[:, 0].tolist(), v[:, 0].tolist(), egos,
                                             strict=True)]
    poses = np.array([(px, py, math.cos(ph), math.sin(ph), pv, ph)
                      for px, py, ph, pv in pose]).T
    runs, ids, pool = _clutter(models[0].false_positives, u[:, 3 * n:], v[:, 0].tolist())
    if n:
        z, seen, multipath = _actors(models, scenes, u, g, x, y, h, v)
        rows = seen.nonzero()[0]  # row-major: run by run, actors in order
        parts_runs, parts_ids = [rows], [_rows([s.actor_id for s in scenes])[:, 1:][seen]]
        parts_z = [z[:, seen]]
        if np.count_nonzero(multipath):
            visible, ghosts = models[0].false_positives.mirror(z[:, multipath])
            parts_runs.append(multipath.nonzero()[0][visible])
            parts_ids.append(np.full(np.count_nonzero(visible), GHOST_ID, dtype=np.int64))
            parts_z.append(ghosts[:, visible])
        runs = np.concatenate((*parts_runs, runs))
        order = np.argsort(runs, kind="stable")  # per run: actors, ghosts, clutter
        runs = runs[order]
        ids = np.concatenate((*parts_ids, ids))[order]
        pool = np.concatenate((*parts_z, pool), axis=1)[:, order]
    _to_world(pool, runs, poses)
    return _split(ids, pool, runs, n_runs)


def _split(ids: np.ndarray, pool: np.ndarray, runs: np.ndarray,
           n_runs: int) -> list[Detections]:
    """Per run, its ids and its (DET_FIELDS, m) block of the pool's columns (sorted by run),
    C-ordered, all in one buffer: field f of the pool's column q, the (q − a)-th of a run
    starting at column a with m columns, lands at DET_FIELDS·a + f·m + (q − a)."""
    counts = np.bincount(runs, minlength=n_runs)
    ends = np.cumsum(counts)
    dest = ((DET_FIELDS - 1) * (ends - counts).take(runs) + np.arange(len(runs))
            + np.arange(DET_FIELDS)[:, None] * counts.take(runs))
    buf = np.empty(pool.size)
    buf[dest] = pool
    out, a = [], 0
    for m, e in zip(counts.tolist(), ends.tolist(), strict=True):
        out.append(Detections(ids[a:e], buf[DET_FIELDS * a:DET_FIELDS * e].reshape(
            DET_FIELDS, m)))
        a = e
    return out
