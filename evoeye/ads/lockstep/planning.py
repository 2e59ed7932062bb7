"""Planning over a batch of runs: `plan_batch` gives every run exactly what its own
`RoutePlanner.plan` gives it, bit for bit, and leaves its planner in the same state.

The planner is stateful (stitching, decision hysteresis, the yield's stop point, the tracks it
proceeds past) and decides in scalar Python over a handful of obstacles, so the decisions stay
per run: `plan_batch` calls the pieces `RoutePlanner.plan` is made of (`_route_s`,
`_start_speed`, `_plausible`, `_decide`, `_ramp`, `_planned`) for each run, in the same order.
What it does once for many runs is the array work between them, all of it elementwise or row
by row, each row with its own run's scalars (ego position, speed, …) as a column:

* the ego's route arc length (`PolylineIndex.project_point`'s arithmetic on arrays);
* every predicted point projected onto the route and tested against the ego's corridor
  (`RoutePlanner._paths`), and the conflict regions and arrival times of the obstacles that
  cross the path (`RoutePlanner._crossings`), on the rows of all runs at once;
* the speed profiles along the route and the trajectories' points and headings on it
  (`speed_profile`, `xy_at`, `heading_at` on (B, P) arrays, a row per run).

Runs are batched only where that is safe: the planner is exactly a `RoutePlanner`, shares the
route index *object* (`PolylineIndex.build` caches it by content, so the runs of one map share
it) and has a config of equal repr, equal derived thresholds and equal plan times (`_key`,
computed once per planner and reused while the planner still holds the objects it was computed
from); a run's predictions are plain arrays of the group's dtypes (concatenation must not
convert them). Any other run and a group of one run are planned by their own planner alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evoeye.ads.lockstep.keys import GroupKeys, bits
from evoeye.ads.messages import Localization, PlannedTrajectory, Predictions
from evoeye.ads.plan_arrays import Crossings, InPath, speed_profile
from evoeye.ads.planning import Planner, RoutePlanner

# below this many runs, the scalar projection of the ego is the cheaper one
_VECTOR_EGO_MIN = 4

_KEYS = GroupKeys("planning")  # what each planner plans by


def plan_batch(
    planners: Sequence[Planner], predictions: Sequence[Predictions],
    egos: Sequence[Localization],
) -> list[PlannedTrajectory]:
    """`[p.plan(pr, e) for p, pr, e in zip(planners, predictions, egos)]`, bit for bit, with the
    array work done once per group of runs that share a route and a config (one planner per
    run: each call updates its planner's state).

    If a run raises, so does `plan_batch`, and every `RoutePlanner` of the batch is left as it
    was (the array work of every group is done before any planner's state changes, and the
    state is put back if a decision raises), so the runs can be planned again one by one.
    Other planners are planned alone, last: those before the one that raised keep what they
    planned."""
    n = len(planners)
    if not n == len(predictions) == len(egos):
        raise ValueError(f"plan_batch needs one planner, predictions and ego per run, got "
                         f"{n}, {len(predictions)}, {len(egos)}")
    if n == 1:  # nothing to share
        p = planners[0]
        saved = [(p, dict(vars(p)))] if type(p) is RoutePlanner else []
        try:
            return [p.plan(predictions[0], egos[0])]
        except BaseException:
            _rewind(saved)
            raise
    if len({id(p) for p in planners}) != n:
        raise ValueError("plan_batch needs a planner per run, got one planner for several")
    out: list[PlannedTrajectory | None] = [None] * n
    groups: dict[tuple, list[int]] = {}
    others = []
    for i, p in enumerate(planners):
        if type(p) is RoutePlanner:
            groups.setdefault(_key(p), []).append(i)
        else:
            others.append(i)
    batches = [(runs, _prepare([planners[i] for i in runs], [predictions[i] for i in runs],
                               [egos[i] for i in runs]))
               for runs in groups.values() if len(runs) > 1]
    alone = [runs[0] for runs in groups.values() if len(runs) == 1]  # nothing to share
    saved = [(planners[i], dict(vars(planners[i]))) for runs in groups.values() for i in runs]
    try:
        for runs, prepared in batches:
            plans = _finish([planners[i] for i in runs], [egos[i] for i in runs], *prepared)
            for i, plan in zip(runs, plans, strict=True):
                out[i] = plan
        for i in alone + others:
            out[i] = planners[i].plan(predictions[i], egos[i])
    except BaseException:
        _rewind(saved)
        raise
    return out  # type: ignore[return-value]  # every slot is filled


def _rewind(saved: list[tuple[RoutePlanner, dict]]) -> None:
    """Put the planners' attributes back (a RoutePlanner replaces its state, never writes into
    it: its attributes as they were are its state as it was)."""
    for p, attributes in saved:
        vars(p).update(attributes)


def _key(p: RoutePlanner) -> tuple:
    """Equal for planners whose array work is the same: the same route index object, configs of
    equal repr (its fields are scalars, whose reprs are exact and tell 0.0 from −0.0), the same
    derived thresholds and plan times (bit for bit)."""
    made = (p.c, p.route, p.t_rel, p._corridor_half, p._cos_aligned, p._half_len)
    return _KEYS.get(p, made, lambda: (
        type(p.c), repr(p.c), id(p.route), bits(p.t_rel), repr(p._corridor_half),
        repr(p._cos_aligned), repr(p._half_len)))


def _prepare(
    planners: list[RoutePlanner], predictions: list[Predictions], egos: list[Localization]
) -> tuple[list[float], list[float], list[Predictions], list[InPath | None]]:
    """What the decisions of runs whose planners share a key start from: the ego's route arc
    length and speed, the plausible predictions and the points in the path (no state
    changes)."""
    s_e = _route_s(planners, egos)
    v = [p._start_speed(e.speed_mps) for p, e in zip(planners, egos, strict=True)]
    plausible = [p._plausible(pr) for p, pr in zip(planners, predictions, strict=True)]
    return s_e, v, plausible, _paths(planners, plausible, s_e, v)


def _finish(
    planners: list[RoutePlanner], egos: list[Localization], s_e: list[float], v: list[float],
    plausible: list[Predictions], paths: list[InPath | None],
) -> list[PlannedTrajectory]:
    """The decisions (per run, updating each planner's state) and the trajectories."""
    decided = [
        p._decide(pr, w, s, vi)
        for p, pr, w, s, vi in zip(planners, plausible, paths, s_e, v, strict=True)
    ]
    return _trajectories(planners, egos, s_e, v, decided)


def _route_s(planners: list[RoutePlanner], egos: list[Localization]) -> list[float]:
    """The route arc length of every ego (`RoutePlanner._route_s`): the float operations of
    `PolylineIndex.project_point`, in its order, on arrays; an ego off the grid, without a
    vertex in reach or not finite takes its planner's own path (which searches, or raises)."""
    if len(planners) < _VECTOR_EGO_MIN:
        return [p._route_s(e.x_m, e.y_m) for p, e in zip(planners, egos, strict=True)]
    r = planners[0].route
    x = np.array([e.x_m for e in egos], dtype=float)
    y = np.array([e.y_m for e in egos], dtype=float)
    gi = np.floor((x - r.x0) * r.inv_cell)  # NaN and ±inf fail the bounds
    gj = np.floor((y - r.y0) * r.inv_cell)
    on = (gi >= 0) & (gi < r.nx) & (gj >= 0) & (gj < r.ny)
    gi, gj = np.where(on, gi, 0.0), np.where(on, gj, 0.0)
    v = np.where(on, r.table.take(((gj * r.nx + gi) * r.sectors).astype(np.int64)), 0)
    dx, dy = x - r.x.take(v), y - r.y.take(v)
    s = (r.g.take(v) + dx * r.tx.take(v) + dy * r.ty.take(v)).tolist()
    return [si if vi else p._route_s(e.x_m, e.y_m)
            for si, vi, p, e in zip(s, v.tolist(), planners, egos, strict=True)]


def _rows_key(p: Predictions) -> tuple | None:
    """The shape and dtypes the batch concatenates a run's predicted rows by, or None unless
    they are plain arrays of n ≥ 1 rows of K ≥ 2 points."""
    x, y, length, width, track = p.x_m, p.y_m, p.length_m, p.width_m, p.track_id
    nd = np.ndarray
    if not (type(x) is nd and type(y) is nd and type(length) is nd and type(width) is nd
            and type(track) is nd and x.ndim == 2 and y.shape == x.shape and x.shape[1] > 1):
        return None
    n = (x.shape[0],)
    if not length.shape == width.shape == track.shape == n:
        return None
    return (x.shape[1], x.dtype, y.dtype, length.dtype, width.dtype, track.dtype)


def _paths(
    planners: list[RoutePlanner], plausible: list[Predictions], s_e: list[float],
    v: list[float],
) -> list[InPath | None]:
    """Every run's predicted points in its path (`RoutePlanner._paths`) with the crossing
    obstacles' conflicts (`RoutePlanner._crossings`), computed for the rows of all runs at once,
    each row with its own run's scalars, then split by run (None where nothing enters)."""
    paths: list[InPath | None] = [None] * len(planners)
    groups: dict[tuple, list[int]] = {}
    for i, p in enumerate(plausible):
        if p.x_m.shape[0] and p.x_m.shape[1] > 1:  # else nothing to react to, as alone
            key = _rows_key(p)
            if key is None:
                paths[i] = planners[i]._paths(p.x_m, p.y_m, p.length_m, p.width_m, s_e[i])
            else:
                groups.setdefault(key, []).append(i)
    for runs in groups.values():
        if len(runs) == 1:
            p = plausible[runs[0]]
            paths[runs[0]] = planners[runs[0]]._paths(p.x_m, p.y_m, p.length_m, p.width_m,
                                                      s_e[runs[0]])
            continue
        ps = [plausible[i] for i in runs]
        counts = [len(p.length_m) for p in ps]
        whole = planners[runs[0]]._paths(
            np.concatenate([p.x_m for p in ps]), np.concatenate([p.y_m for p in ps]),
            np.concatenate([p.length_m for p in ps]), np.concatenate([p.width_m for p in ps]),
            np.repeat(np.array([s_e[i] for i in runs], dtype=float), counts)[:, None],
        )
        if whole is None:  # no obstacle of any run enters its path
            continue
        ends = np.cumsum(counts)
        starts = ends - counts
        enters = np.logical_or.reduceat(whole.enters, starts).tolist()  # no run without rows
        cross = whole.cross.nonzero()[0]  # (m,) the crossing rows of all runs, run by run
        crossings, c_ends = None, [0] * len(runs)
        if len(cross):
            c_ends = np.searchsorted(cross, ends).tolist()
            crossings = _crossings(planners, runs, ps, whole, cross, c_ends, s_e, v)
        c0 = 0
        for j, i in enumerate(runs):
            a, b, c1 = int(starts[j]), int(ends[j]), c_ends[j]
            if enters[j]:
                own = None if c1 == c0 or crossings is None else Crossings._make(
                    f[c0:c1] for f in crossings)
                paths[i] = InPath(*[f[a:b] for f in whole[:-1]], crossings=own)
            c0 = c1
    return paths


def _crossings(
    planners: list[RoutePlanner], runs: list[int], ps: list[Predictions], whole: InPath,
    cross: np.ndarray, c_ends: list[int], s_e: list[float], v: list[float],
) -> Crossings:
    """The conflicts of the crossing rows `cross` of the runs `runs` (c_ends: where each run's
    rows end in `cross`), each row with its run's scalars as `_react` passes them alone."""
    head = planners[runs[0]]
    counts = np.diff(c_ends, prepend=0)
    dt, s, vi, vc, hold = [], [], [], [], []
    for i, p in zip(runs, ps, strict=True):
        planner = planners[i]
        dt.append(p.dt_s)
        s.append(s_e[i])
        vi.append(v[i])
        vc.append(max(planner.cruise_mps, v[i]))
        hold.append(planner._hold_id)
    scalars = np.repeat(np.array([dt, s, vi, vc]).T, counts, axis=0)  # (m, 4)
    ids = np.concatenate([p.track_id for p in ps]).take(cross)
    margin = np.full(len(cross), head.c.gap_margin_s)  # each run's, for their configs agree
    c0 = 0
    for i, c1 in zip(runs, c_ends, strict=True):
        if c1 > c0 and len(planners[i]._proceeding):
            margin[c0:c1] = planners[i]._margin(ids[c0:c1], planners[i]._proceeding)
        c0 = c1
    hold = np.repeat(np.array(hold), counts)
    held = (ids == hold) & (hold >= 0)  # as alone: no row held where the run holds none
    return head._crossings(whole, cross, ids, scalars[:, 0], scalars[:, 1], scalars[:, 2],
                           scalars[:, 3], margin, held)


def _trajectories(
    planners: list[RoutePlanner], egos: list[Localization], s_e: list[float], v: list[float],
    decided: list[tuple[float, str, int, float]],
) -> list[PlannedTrajectory]:
    """Every run's trajectory: the speed profiles as rows of (B, P) arrays (each run's scalars
    a column), their points and headings on the route in one call each."""
    head = planners[0]
    a, decision, leader, target = zip(*decided, strict=True)
    t_end, v_end = zip(*(p._ramp(vi, ai, d) for p, vi, ai, d in zip(
        planners, v, a, decision, strict=True)), strict=True)
    speed, accel, s = speed_profile(head.t_rel, *[np.array(c, dtype=float)[:, None] for c in (
        v, a, t_end, v_end, s_e)])
    x, y = head.route.xy_at(s)
    heading = head.route.heading_at(s)
    return [
        p._planned(egos[j], v[j], decision[j], target[j], leader[j], x[j], y[j], heading[j],
                   speed[j], accel[j])
        for j, p in enumerate(planners)
    ]
