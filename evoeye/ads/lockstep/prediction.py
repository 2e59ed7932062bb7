"""Prediction over a batch of runs: one `IntentPredictor` pass for the obstacles of every run.

Prediction is stateless given the predictor's map and config, and each run builds its own
predictor of the same map, so the obstacles of runs whose predictors agree on both are
concatenated and predicted at once by one of them (`IntentPredictor.modes`). Every step there is
elementwise per obstacle (lane lookup, projection, intents, interpolation along the paths) or
per row of the obstacle's own M + 4 mode columns (M, the lane graph's paths per lane, is the same
for the same graph): a run's rows come out with the bits its own predictor gives them. The one
step across obstacles, the ordering of the rows, sorts by obstacle and then by the key the run
computes itself, on its own obstacle index (`first`), so each run keeps its own order.

Runs are batched only where that is safe: the predictor is exactly an `IntentPredictor`; it
shares the lane index and lane graph *objects* (both cached by content, so the runs of one map
share them) and has equal lane lengths, give-way flags and horizon, and a config of equal repr
(`_key`, computed once per predictor and reused while the predictor still holds the objects it
was computed from: a predictor's arrays are never written after it is built); the obstacle
arrays are plain 1-D arrays of the group's dtypes (concatenation must not convert them). Any
other run and a group of one run are predicted by their own predictor, and of a group of runs
without obstacles, the first (the others get empty arrays of the same dtypes and shapes).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evoeye.ads.lockstep.keys import GroupKeys, bits
from evoeye.ads.messages import PREDICTION_MODES, Localization, Obstacles, Predictions
from evoeye.ads.prediction import IntentPredictor, Predictor

_KEYS = GroupKeys("prediction")  # what each predictor predicts by


def predict_batch(
    predictors: Sequence[Predictor], obstacles: Sequence[Obstacles],
    egos: Sequence[Localization],
) -> list[Predictions]:
    """`[p.predict(o, e) for p, o, e in zip(predictors, obstacles, egos)]`, bit for bit, with
    the array work done once per group of runs that share a map and a config."""
    if not len(predictors) == len(obstacles) == len(egos):
        raise ValueError(f"predict_batch needs one predictor, obstacle list and ego per run, got "
                         f"{len(predictors)}, {len(obstacles)}, {len(egos)}")
    if len(predictors) == 1:  # nothing to share
        return [predictors[0].predict(obstacles[0], egos[0])]
    out: list[Predictions | None] = [None] * len(predictors)
    groups: dict[tuple, tuple[IntentPredictor, list[int], list[tuple]]] = {}
    for i, (p, o) in enumerate(zip(predictors, obstacles, strict=True)):
        arrays = _arrays(o) if type(p) is IntentPredictor else None
        if arrays is None:  # another predictor, or unusual arrays: its own
            out[i] = p.predict(o, egos[i])
            continue
        # the dtypes: concatenation must not convert them, and they make the empty arrays
        key = (len(arrays[0]) == 0, _key(p), *[a.dtype for a in arrays])
        group = groups.get(key)
        if group is None:
            groups[key] = (p, [i], [arrays])
        else:
            group[1].append(i)
            group[2].append(arrays)
    for (empty, *_), (p, runs, arrays) in groups.items():
        if len(runs) == 1 or empty:  # an empty run's arrays are the first's (n = 0 is no data)
            first = out[runs[0]] = p.predict(obstacles[runs[0]], egos[runs[0]])
            for i in runs[1:]:
                out[i] = _empty_like(first, obstacles[i].t_s)
            continue
        preds = _predict_group(p, [obstacles[i] for i in runs], arrays)
        for i, pred in zip(runs, preds, strict=True):
            out[i] = pred
    return out  # type: ignore[return-value]  # every slot is filled


def _arrays(o: Obstacles) -> tuple[np.ndarray, ...] | None:
    """The arrays prediction reads (positions, heading, velocity, track id, size), or None unless
    they are plain 1-D arrays of one length."""
    arrays = (o.x_m, o.y_m, o.heading_rad, o.vx_mps, o.vy_mps, o.track_id, o.length_m,
              o.width_m)
    n = len(o.x_m)
    for a in arrays:
        if type(a) is not np.ndarray or a.ndim != 1 or len(a) != n:
            return None
    return arrays


def _key(p: IntentPredictor) -> tuple:
    """Equal for predictors that predict alike: the same lane index and lane graph objects (both
    cached by content, so the runs of one map share them), equal lane lengths, give-way flags
    and horizon, and configs of equal repr (its fields are scalars, whose reprs are exact and
    tell 0.0 from −0.0 and 1 from 1.0)."""
    graph, lane_len, gives_way = (getattr(p, a, None) for a in ("graph", "lane_len", "gives_way"))
    made = (p.c, p.k, p.t_s, p.lanes, graph, lane_len, gives_way)
    return _KEYS.get(p, made, lambda: (
        type(p.c), repr(p.c), p.k, bits(p.t_s), id(p.lanes), id(graph), bits(lane_len),
        bits(gives_way)))


def _empty_like(pred: Predictions, t_s: float) -> Predictions:
    """The predictions of no obstacles at t_s, given those of no obstacles with the same dtypes
    by the same kind of predictor (empty views of its arrays: the same dtypes and shapes)."""
    return Predictions(t_s=t_s, dt_s=pred.dt_s, track_id=pred.track_id[:0], model=[],
                       mode_prob=pred.mode_prob[:0], length_m=pred.length_m[:0],
                       width_m=pred.width_m[:0], x_m=pred.x_m[:0], y_m=pred.y_m[:0])


def _predict_group(
    p: IntentPredictor, obstacles: list[Obstacles], arrays: list[tuple[np.ndarray, ...]],
) -> list[Predictions]:
    """The predictions of runs whose predictors all predict as p does (`arrays`: each run's, by
    `_arrays`)."""
    counts = np.array([len(a[0]) for a in arrays])
    ox, oy, heading, vx, vy, track, length, width = (
        np.concatenate(f) for f in zip(*arrays, strict=True))
    n = len(ox)
    ends = counts.cumsum()
    if p.lanes is None:  # a map without lanes: constant velocity, one row per obstacle
        t = p.t_s
        x = ox[:, None] + vx[:, None] * t  # (n, K)
        y = oy[:, None] + vy[:, None] * t
        rows, mode, prob = np.arange(n), np.zeros(n, np.int64), np.ones(n)
        bounds = [0, *ends.tolist()]
    else:
        first = np.repeat(ends - counts, counts)  # (n,) each obstacle's run's first obstacle
        rows, mode, prob, x, y = p.modes(ox, oy, heading, vx, vy, first)
        bounds = [0, *rows.searchsorted(ends).tolist()]  # rows are sorted by obstacle
    track, length, width = track.take(rows), length.take(rows), width.take(rows)
    model = [PREDICTION_MODES[i] for i in mode.tolist()]
    dt = p.c.dt_s
    return [
        Predictions(t_s=o.t_s, dt_s=dt, track_id=track[a:b], model=model[a:b],
                    mode_prob=prob[a:b], length_m=length[a:b], width_m=width[a:b],
                    x_m=x[a:b], y_m=y[a:b])
        for o, a, b in zip(obstacles, bounds[:-1], bounds[1:], strict=True)
    ]
