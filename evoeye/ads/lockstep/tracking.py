"""Tracking over a batch of runs: one `CVTracker` step for the tracks of every run at once.

`track_batch` gives every run the `Obstacles` its own `TrackingPerception.track` gives it, bit
for bit, and leaves its latency buffer and tracker exactly as that call leaves them. The
tracks of all runs of a group (runs whose trackers and perceptions share a configuration,
`_key`) are concatenated, run after run, and every step that is elementwise per track or per
(track, detection) pair is done once for them all: the constant-velocity prediction, the
misses, the gating distances, the Kalman update of the associated pairs
(`evoeye.ads.tracking.update_tracks`), the new tracks (`new_tracks`), pruning, and the
published rows with their latency lead and confidence (`CVTracker.confidence`).

What stays per run is what is not elementwise: `linear_sum_assignment` on the run's own (m, k)
gated cost, and the covariance propagation `cov_a @ P`, a matmul whose bits may depend on the
BLAS kernel and so on the operand's width and layout: it is called on the run's own state
block, as the run's own step calls it. For the same reason a run's new state array gets the
memory layout its own step would give it (C or Fortran order depends on how the track set
changed): the array is made by the same numpy calls on the same arrays (the in-place
update, the concatenation with the new tracks, the boolean selection of the survivors), and
only its values are taken from the batch.

The runs of a small group (at most `ALONE_MAX`) are tracked by their own `track`: the batch's
fixed cost, some 180 calls on small arrays (≈ 250 µs on the machine of BENCHMARKS.md, against
50–100 µs for a run's own `track`), pays only from about five runs on
(tests/ads/bench_lockstep_tracking.py).

Exception safety: the groups' array work is done on copies, before any buffer or tracker
changes; then the runs tracked alone are tracked, each put back as it was (buffer, state
values, arrays, next id) if one of them raises; only then are the groups' results assigned,
by assignments and copies that cannot fail. So if `track_batch` raises, no run has changed
and the runs can be tracked again one by one. A perception other than exactly a
`TrackingPerception` with a `CVTracker`, or one given twice, makes it raise before anything
changes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from evoeye.ads.detections import DET_FIELDS, DET_X, DET_Y, Detections
from evoeye.ads.lockstep.keys import GroupKeys, bits
from evoeye.ads.messages import Obstacles
from evoeye.ads.perception import TrackingPerception
from evoeye.ads.tracking import (
    HEADING,
    HITS,
    LENGTH,
    MISSES,
    P_PP,
    TRACK_FIELDS,
    UNASSIGNABLE,
    VX,
    VY,
    WIDTH,
    CVTracker,
    X,
    Y,
    new_tracks,
    update_tracks,
)
from evoeye.scene import SceneState

# groups of at most this many runs are tracked by each run's own `track`
ALONE_MAX = 4

_KEYS = GroupKeys("tracking")  # how each perception tracks


def track_batch(
    perceptions: Sequence[TrackingPerception], scenes: Sequence[SceneState],
    detections: Sequence[Detections],
) -> list[Obstacles]:
    """`[p.track(s, d) for p, s, d in zip(perceptions, scenes, detections)]`, bit for bit, with
    the array work done once per group of runs that share a tracker configuration.

    If it raises, no perception has changed (see the module docstring)."""
    n = len(perceptions)
    if not n == len(scenes) == len(detections):
        raise ValueError(f"track_batch needs one perception, scene and detection list per run, "
                         f"got {len(perceptions)}, {len(scenes)}, {len(detections)}")
    groups: dict[tuple, list[int]] = {}
    for i, p in enumerate(perceptions):
        groups.setdefault(_key(p), []).append(i)
    if len({id(p) for p in perceptions} | {id(p.tracker) for p in perceptions}) < 2 * n:
        raise ValueError("track_batch got a perception or tracker twice: each run tracks with "
                         "its own")
    out: list[Obstacles | None] = [None] * n
    commits: list[tuple] = []
    alone = []
    for runs in groups.values():
        if len(runs) <= ALONE_MAX:
            alone += runs
            continue
        obs = _track_group([perceptions[i] for i in runs], [detections[i] for i in runs],
                           [float(scenes[i].t_s) for i in runs], commits)
        for i, o in zip(runs, obs, strict=True):
            out[i] = o
    saved = []
    try:
        for i in alone:
            saved.append(_saved(perceptions[i]))
            out[i] = perceptions[i].track(scenes[i], detections[i])
    except BaseException:
        for s in reversed(saved):
            _put_back(*s)
        raise
    for commit in commits:  # none of this can raise
        _commit(*commit)
    return out  # type: ignore[return-value]  # every slot is filled


def _key(p: TrackingPerception) -> tuple:
    """Equal for perceptions that track alike: the tracker's config and frame time, the range
    the confidence is scaled by and the latency lead (reprs: exact, they tell 0.0 from −0.0)."""
    if type(p) is not TrackingPerception or type(p.tracker) is not CVTracker:
        raise TypeError(f"track_batch tracks with a TrackingPerception and a CVTracker, not "
                        f"{type(p).__name__} with {type(getattr(p, 'tracker', None)).__name__}")
    t = p.tracker
    made = (t, t.c, t.dt_s, t._cov_q, t._miss_limit, p.range_m, p.lead_s)
    return _KEYS.get(p, made, lambda: (
        type(t.c), repr(t.c), repr(t.dt_s), bits(t._cov_q), bits(t._miss_limit),
        repr(p.range_m), repr(p.lead_s)))


def _saved(p: TrackingPerception) -> tuple:
    """What `track` may change of a perception, to put it back (`_put_back`)."""
    t = p.tracker
    return (p, list(p._pending), t.state, t.state.copy(), t.track_id, t.confirmed, t._next_id)


def _put_back(p: TrackingPerception, pending: list, state: np.ndarray, values: np.ndarray,
              track_id: np.ndarray, confirmed: np.ndarray, next_id: int) -> None:
    p._pending.clear()
    p._pending.extend(pending)
    state[...] = values  # `step` changes the state array in place before it replaces it
    t = p.tracker
    t.state, t.track_id, t.confirmed, t._next_id = state, track_id, confirmed, next_id


def _track_group(ps: list[TrackingPerception], dets: list[Detections], t_s: list[float],
                 commits: list[tuple]) -> list[Obstacles]:
    """The Obstacles of runs that share a `_key`; what each run's buffer and tracker become is
    appended to `commits` (nothing is changed here)."""
    trackers = [p.tracker for p in ps]
    olds = [t.state for t in trackers]
    zs = []  # what each tracker steps with: the oldest in the buffer once `d` is appended to it
    for p, d in zip(ps, dets, strict=True):
        pending = p._pending
        oldest = len(pending) + 1 - pending.maxlen
        zs.append(None if oldest < 0 else pending[oldest].z if oldest < len(pending) else d.z)
    stepping = [j for j, z in enumerate(zs) if z is not None]
    if not stepping:  # the first frames, before the latency buffer is full
        src = np.concatenate(olds, axis=1)
        tid = np.concatenate([t.track_id for t in trackers])
        confirmed = np.concatenate([t.confirmed for t in trackers])
        counts = [s.shape[1] for s in olds]
        per_run = []
    else:
        src, tid, confirmed, counts, per_run = _step([trackers[j] for j in stepping],
                                                     [olds[j] for j in stepping],
                                                     [zs[j] for j in stepping])
        if len(stepping) < len(ps):  # the stepped runs' tracks and the others' as they are
            bounds = np.concatenate(([0], np.cumsum(counts))).tolist()
            blocks = [(s, t.track_id, t.confirmed) for s, t in zip(olds, trackers, strict=True)]
            for i, j in enumerate(stepping):
                a, b = bounds[i], bounds[i + 1]
                blocks[j] = (src[:, a:b], tid[a:b], confirmed[a:b])
            src = np.concatenate([b[0] for b in blocks], axis=1)
            tid = np.concatenate([b[1] for b in blocks])
            confirmed = np.concatenate([b[2] for b in blocks])
            counts = [b[0].shape[1] for b in blocks]
    if src.dtype != np.float64 or src.shape[0] != TRACK_FIELDS:
        raise TypeError(f"track states must be float64 ({TRACK_FIELDS}, m) arrays")
    it = iter(per_run)
    for p, d, z, t in zip(ps, dets, zs, trackers, strict=True):
        commits.append((p, d) if z is None else (p, d, t, *next(it)))
    return _publish(ps[0], trackers[0], src, tid, confirmed, counts, t_s)


def _step(trackers: list[CVTracker], olds: list[np.ndarray], zs: list[np.ndarray]) -> tuple:
    """`CVTracker.step` for every tracker (all of one `_key`; `olds` their states), each with
    its detections z (10, k): the states after it (13, ·) run after run, their track ids and
    confirmed flags, the number of tracks of each run, and per run what its tracker becomes
    (`_commit`'s arguments)."""
    t0 = trackers[0]
    c = t0.c
    nr = len(trackers)
    m_l = [s.shape[1] for s in olds]
    k_l = [z.shape[1] for z in zs]
    m, k = np.array(m_l, dtype=np.int64), np.array(k_l, dtype=np.int64)
    toff = np.cumsum(m) - m
    doff = np.cumsum(k) - k
    s = np.concatenate(olds, axis=1)  # a copy: the runs' own states stay as they are
    z = np.concatenate(zs, axis=1)
    if s.dtype != np.float64 or z.dtype != np.float64 or z.shape[0] != DET_FIELDS:
        raise TypeError(f"track states and detections must be float64 ({TRACK_FIELDS}, m) and "
                        f"({DET_FIELDS}, k) arrays, got {s.dtype} {s.shape}, {z.dtype} {z.shape}")
    # predict; the covariance by each run's own matmul on its own block, as its step does it
    s[X:VX] += s[VX:P_PP] * t0.dt_s
    cov = [t._cov_a @ old[P_PP:HEADING] for t, old, mj in zip(trackers, olds, m_l, strict=True)
           if mj]
    if cov:
        s[P_PP:HEADING] = np.concatenate(cov, axis=1)
    s[P_PP:HEADING] += t0._cov_q
    s[MISSES] += 1.0
    # associate: gated distances of every (track, detection) pair of a run, then each run's own
    # assignment on its (m, k) block
    matched_t = matched_d = np.zeros(0, dtype=np.int64)
    both = [j for j in range(nr) if m_l[j] and k_l[j]]
    if both:
        track_run = np.repeat(np.arange(nr), m)
        kt = k.take(track_run)  # (M,) each track's run's number of detections
        first_pair = np.cumsum(kt) - kt  # (M,) the track's first pair, track after track
        gt = np.repeat(np.arange(kt.size), kt)  # (P,) the pair's track in s …
        gd = np.arange(gt.size) - np.repeat(first_pair - doff.take(track_run), kt)  # … in z
        cost = np.hypot(s[X].take(gt) - z[DET_X].take(gd), s[Y].take(gt) - z[DET_Y].take(gd))
        gate = c.gate_m
        gated = np.where(cost <= gate, cost, UNASSIGNABLE)
        fp = first_pair.tolist()
        rows, cols = zip(*[linear_sum_assignment(
            gated[fp[a]:fp[a] + m_l[j] * k_l[j]].reshape(m_l[j], k_l[j]))
            for j, a in zip(both, toff.take(both).tolist(), strict=True)], strict=True)
        counts = [len(r) for r in rows]
        matched_t = np.repeat(toff.take(both), counts) + np.concatenate(rows)
        cols = np.concatenate(cols)
        ok = cost.take(first_pair.take(matched_t) + cols) <= gate
        matched_d = np.repeat(doff.take(both), counts) + cols
        if np.count_nonzero(ok) < ok.size:
            matched_t, matched_d = matched_t[ok], matched_d[ok]
    if matched_t.size:
        upd = s[:, matched_t]
        update_tracks(upd, z[:, matched_d])
        s[:, matched_t] = upd
    # new tracks for the unassociated detections, after their run's tracks
    fresh = np.ones(z.shape[1], dtype=bool)
    fresh[matched_d] = False
    born_run = np.repeat(np.arange(nr), k)[fresh]
    born = np.bincount(born_run, minlength=nr)
    next_id = np.array([t._next_id for t in trackers], dtype=np.int64)
    first_born = np.cumsum(born) - born
    new_ids = np.repeat(next_id - first_born, born) + np.arange(born_run.size)
    all_s = np.concatenate((s, new_tracks(z[:, fresh])), axis=1)
    all_tid = np.concatenate([t.track_id for t in trackers] + [new_ids])
    col_run = np.concatenate((np.repeat(np.arange(nr), m), born_run))
    order = np.argsort(col_run, kind="stable")  # run after run: its tracks, then its new ones
    # prune
    misses = all_s[MISSES]
    alive = misses <= t0._miss_limit.take((all_s[HITS] >= c.confirm_hits).view(np.int8))
    over = np.bincount(col_run[misses > c.tentative_max_misses], minlength=nr) > 0
    prune = over & (np.bincount(col_run[~alive], minlength=nr) > 0)
    keep = alive | ~prune[col_run]
    sel = order[keep[order]]
    fin = all_s.take(sel, axis=1)
    ftid = all_tid[sel]
    fconf = fin[HITS] >= c.confirm_hits
    fcounts = np.bincount(col_run[sel], minlength=nr).tolist()
    seg = np.concatenate(([0], np.cumsum(m + born))).tolist()
    per_run = []
    a = 0
    for j, (old, t, nb, pr) in enumerate(zip(olds, trackers, born.tolist(), prune.tolist(),
                                             strict=True)):
        b = a + fcounts[j]
        new = tid = None
        if nb or pr:  # the array the run's own step makes, with the values from the batch
            new = np.concatenate((old, np.zeros((TRACK_FIELDS, nb))), axis=1) if nb else old
            if pr:
                new = new[:, alive[order[seg[j]:seg[j + 1]]]]
            new[...] = fin[:, a:b]
            tid = ftid[a:b]
        per_run.append((new, fin[:, a:b], tid, fconf[a:b], t._next_id + nb))
        a = b
    return fin, ftid, fconf, fcounts, per_run


def _commit(p: TrackingPerception, d: Detections, trk: CVTracker | None = None,
            new: np.ndarray | None = None, values: np.ndarray | None = None,
            tid: np.ndarray | None = None, confirmed: np.ndarray | None = None,
            next_id: int = 0) -> None:
    """What the run's own `track` changes: the buffer, and the tracker if it stepped."""
    p._pending.append(d)
    if trk is None:
        return
    if new is None:  # the same tracks: updated in place, as its own step does
        trk.state[...] = values
    else:
        trk.state = new
        trk.track_id = tid
    trk.confirmed = confirmed
    trk._next_id = next_id


def _publish(p: TrackingPerception, trk: CVTracker, s: np.ndarray, tid: np.ndarray,
             confirmed: np.ndarray, counts: list[int], t_s: list[float]) -> list[Obstacles]:
    """Each run's Obstacles from the states s (13, ·) of the runs' tracks, run after run
    (`counts` each), as `TrackingPerception.track` publishes them."""
    rows = confirmed.nonzero()[0]
    pub = s.take(rows, axis=1)  # C-ordered: every published row is contiguous
    if p.lead_s:
        pub[X:VX] += pub[VX:VY + 1] * p.lead_s
    conf = trk.confidence(pub, p.range_m)
    ptid = tid[rows]
    nr = len(counts)
    per = np.bincount(np.repeat(np.arange(nr), counts)[rows], minlength=nr)
    bounds = np.concatenate(([0], np.cumsum(per))).tolist()
    x, y, heading, vx, vy, length, width = (pub[f] for f in (X, Y, HEADING, VX, VY, LENGTH,
                                                             WIDTH))
    return [
        Obstacles(t_s=t, track_id=ptid[a:b], obj_class=["car"] * (b - a), x_m=x[a:b],
                  y_m=y[a:b], heading_rad=heading[a:b], vx_mps=vx[a:b], vy_mps=vy[a:b],
                  length_m=length[a:b], width_m=width[a:b], confidence=conf[a:b])
        for t, a, b in zip(t_s, bounds[:-1], bounds[1:], strict=True)
    ]
