"""Prediction: multi-modal hypotheses per tracked obstacle, each with a probability.

An obstacle within `lane_match_radius_m` of a lane centre (of a lane heading roughly its way)
gets these modes:

* "lane": it follows the lane's centre line at its along-lane speed — one row per continuation
  of the lane where the map branches (straight on, a turn), the continuations sharing the
  lane-keeping probability by how well the obstacle's heading matches each continuation's
  tangent a little ahead (`turn_lookahead_s`): a turn shows only once the car starts turning;
* "left" / "right": a lane change into the neighbouring lane (where there is one), from its
  current offset over `lane_change_duration_s` per lane width, with log-odds
  v_lat / intent_lat_speed_scale_mps + offset / intent_offset_scale_m − intent_change_bias
  against lane keeping.

* "yield": on a lane that gives way to the route (the map's rule of the road), within
  `yield_range_m` of the lane's end, it brakes to stop there. Its probability is
  `yield_prior` while stopping needs at most about `yield_decel_mps2`, and fades as the braking
  it would need grows: a driver who ignores the rule shows it only by not slowing down, late.
  The lane's other modes share what is left.

Any other obstacle gets one "cv" (constant velocity) mode. Modes below `min_mode_prob` are
dropped, except each obstacle's most probable one. The hypotheses can be wrong, as a real
predictor's are: a cut-in is likely only once lateral motion shows, a turn once the heading
turns, and a driver who changes their mind is not foreseen.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from evoeye.ads.config import PredictionConfig
from evoeye.ads.geometry import PolylineIndex
from evoeye.ads.lanes import LaneGraph
from evoeye.ads.messages import PREDICTION_MODES, Localization, Obstacles, Predictions
from evoeye.scene import RoadMap

HEADING_SECTORS = 8  # the lane grid keeps the nearest lane per 45° heading sector
CV, LANE, LEFT, RIGHT, YIELD = range(5)  # indices into PREDICTION_MODES
MODE_AFTER_PATHS = np.array([LANE, LEFT, RIGHT, CV, YIELD])  # the mode of columns M − 1 … M + 3
_GRAPHS: dict[tuple, LaneGraph] = {}  # lane graphs by (lane index, parameters)
GRAPH_CACHE_MAX = 16


class Predictor(Protocol):
    """Predicts the future positions of tracked obstacles."""

    def predict(self, obstacles: Obstacles, ego: Localization) -> Predictions: ...


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.minimum(np.maximum(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


class IntentPredictor:
    """Lane keeping / lane changes / lane continuations with probabilities; CV off the lanes."""

    def __init__(self, road_map: RoadMap, config: PredictionConfig) -> None:
        c = config
        self.c = c
        self.k = int(round(c.horizon_s / c.dt_s))
        self.t_s = (np.arange(self.k) + 1.0) * c.dt_s  # (K,)
        self.lanes: PolylineIndex | None = None
        if road_map.lanes:  # a map without lanes: everything is "cv"
            self.lanes = PolylineIndex.build(
                [lane.points for lane in road_map.lanes], c.lane_resample_m,
                c.lane_match_radius_m, c.grid_cell_m, HEADING_SECTORS,
            )
            key = (self.lanes, c.successor_join_m, c.lane_resample_m)  # the index: by identity
            graph = _GRAPHS.get(key)
            if graph is None:
                graph = LaneGraph.build(road_map.lanes, self.lanes, c.successor_join_m,
                                        c.lane_resample_m)
                if len(_GRAPHS) >= GRAPH_CACHE_MAX:
                    _GRAPHS.pop(next(iter(_GRAPHS)))
                _GRAPHS[key] = graph
            self.graph = graph
            self.lane_len = np.array([float(ln.s_m[-1]) for ln in road_map.lanes])  # (L,)
            self.gives_way = np.array([ln.yields_to_route for ln in road_map.lanes])  # (L,)

    def predict(self, obstacles: Obstacles, ego: Localization) -> Predictions:
        t = self.t_s
        n = len(obstacles.x_m)
        ox, oy = obstacles.x_m, obstacles.y_m  # (n,)
        vx, vy = obstacles.vx_mps, obstacles.vy_mps
        if n == 0 or self.lanes is None:
            x = ox[:, None] + vx[:, None] * t  # (n, K) constant velocity
            y = oy[:, None] + vy[:, None] * t
            return self._message(obstacles, np.arange(n), np.zeros(n, np.int64), np.ones(n), x, y)
        obs, mode, prob, x, y = self.modes(ox, oy, obstacles.heading_rad, vx, vy)
        return self._message(obstacles, obs, mode, prob, x, y)

    def modes(
        self, ox: np.ndarray, oy: np.ndarray, heading: np.ndarray, vx: np.ndarray,
        vy: np.ndarray, first: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The rows (obstacle, mode, probability, x (r, K), y (r, K)) of n ≥ 1 obstacles on a
        map with lanes. Every step is elementwise per obstacle or per row of the obstacle's own
        (M + 4) columns, except the ordering: so `first` ((n,), the index of the first obstacle
        of each obstacle's run) lets the obstacles of several runs be predicted at once
        (`evoeye.ads.lockstep.prediction`), each run ordered by its own sort key."""
        c = self.c
        t = self.t_s
        lanes, graph = self.lanes, self.graph
        v = lanes.candidates(ox, oy, heading)  # (n,) nearest lane heading our way
        g, lat, tx, ty = lanes.project(ox, oy, v)
        lane = lanes.line.take(v)  # −1: no lane
        on = (lane >= 0) & (np.abs(lat) <= c.lane_match_radius_m)
        lane = np.where(on, lane, 0)
        v_along = np.maximum(vx * tx + vy * ty, 0.0)
        v_lat = tx * vy - ty * vx  # to the left of the lane

        # lane-change intent against lane keeping (softmax over keep, left, right)
        evidence = v_lat * (1.0 / c.intent_lat_speed_scale_mps) + lat * (
            1.0 / c.intent_offset_scale_m)
        evidence = np.minimum(np.maximum(evidence, -30.0), 30.0)  # off the lanes, lat is huge
        w_left = np.exp(evidence - c.intent_change_bias) * graph.has_left.take(lane)
        w_right = np.exp(-evidence - c.intent_change_bias) * graph.has_right.take(lane)
        p_keep = on / (1.0 + w_left + w_right)  # 0 off the lanes

        # continuations: heading against each path's tangent a little ahead
        paths = graph.lane_paths.take(lane, axis=0)  # (n, M) path ids, −1 padded
        s = g - lanes.offset.take(lane)  # arc length along the lane
        m = paths.shape[1]
        if m == 1:  # no lane branches: lane keeping is one mode
            p_path = p_keep[:, None]
        else:
            ahead = s + np.maximum(v_along * c.turn_lookahead_s, c.turn_lookahead_min_m)
            path_off = graph.paths.offset.take(np.maximum(paths, 0))  # (n, M)
            dh = graph.paths.heading_at(path_off + ahead[:, None]) - heading[:, None]
            dh = (dh + np.pi) % (2.0 * np.pi) - np.pi
            w = np.exp(dh * dh * (-0.5 / c.turn_heading_sigma_rad**2)) * (paths >= 0)
            p_path = w * (p_keep / np.maximum(w.sum(axis=1), 1e-12))[:, None]  # (n, M)

        # give way: P(it stops at its lane's end), from the braking that stopping would need
        to_end = self.lane_len.take(lane) - s  # (n,) to the lane's end (its stop line)
        may_yield = on & self.gives_way.take(lane) & (to_end > 0.0) & (to_end <= c.yield_range_m)
        stop_m = np.maximum(to_end, 0.5)  # (n,) where a yielding car stops, at least 0.5 m on
        need = v_along * v_along / (2.0 * stop_m)  # (n,) m/s²
        p_yield = may_yield * c.yield_prior / (
            1.0 + np.exp(np.minimum((need - c.yield_decel_mps2) / c.yield_decel_scale_mps2, 50.0)))
        go = 1.0 - p_yield

        # rows (obstacle, mode, probability): columns lane continuations, left, right, cv, yield
        p_all = np.concatenate((p_path * go[:, None], (w_left * p_keep * go)[:, None],
                                (w_right * p_keep * go)[:, None], (~on)[:, None],
                                (on * p_yield)[:, None]), axis=1)  # (n, M + 4)
        best = p_all.max(axis=1, keepdims=True)
        obs, col = ((p_all >= np.minimum(best, c.min_mode_prob)) & (p_all > 0.0)).nonzero()
        prob = p_all[obs, col]
        if first is None:
            order = (obs - 0.5 * prob).argsort(kind="stable")  # per obstacle, most probable first
        else:  # by obstacle, then the key each run computes (on its own obstacle index)
            order = np.lexsort(((obs - first.take(obs)) - 0.5 * prob, obs))
        obs, col, prob = obs.take(order), col.take(order), prob.take(order)
        mode = MODE_AFTER_PATHS.take(np.maximum(col - (m - 1), 0))  # col m → LEFT, m+1 …
        x = np.empty((len(obs), self.k))  # (r, K)
        y = np.empty((len(obs), self.k))
        along = s.take(obs)[:, None] + v_along.take(obs)[:, None] * t  # (r, K)
        is_path = mode == LANE
        if np.count_nonzero(is_path):
            p_ids = paths[obs[is_path], col[is_path]]
            px, py = graph.paths.xy_at(graph.paths.offset.take(p_ids)[:, None] + along[is_path])
            x[is_path], y[is_path] = px, py
        is_cv = mode == CV
        if np.count_nonzero(is_cv):
            o = obs[is_cv]
            x[is_cv] = ox.take(o)[:, None] + vx.take(o)[:, None] * t
            y[is_cv] = oy.take(o)[:, None] + vy.take(o)[:, None] * t
        stops = mode == YIELD
        if np.count_nonzero(stops):  # brake evenly to a stop at the lane's end
            o = obs[stops]
            v0, d_end = v_along.take(o)[:, None], stop_m.take(o)[:, None]
            t_stop = 2.0 * d_end / np.maximum(v0, 1e-6)  # (r, 1)
            tt = np.minimum(t, t_stop)
            ds = v0 * tt - 0.5 * (v0 / t_stop) * tt * tt
            gl = lanes.offset.take(lane.take(o))[:, None] + s.take(o)[:, None] + ds
            x[stops], y[stops] = lanes.xy_at(gl)
        change = (mode == LEFT) | (mode == RIGHT)
        if np.count_nonzero(change):
            o = obs[change]
            gl = lanes.offset.take(lane.take(o))[:, None] + along[change]
            cx, cy = lanes.xy_at(gl)
            hd = lanes.heading_at(gl)
            width = graph.width_m.take(lane.take(o))
            target = np.where(mode[change] == LEFT, width, -width)[:, None]
            d0 = lat.take(o)[:, None]
            dur = c.lane_change_duration_s * np.abs(target - d0) / width[:, None]
            d = d0 + (target - d0) * _smoothstep(t / np.maximum(dur, c.dt_s))
            x[change], y[change] = cx - d * np.sin(hd), cy + d * np.cos(hd)
        return obs, mode, prob, x, y

    def _message(
        self, obstacles: Obstacles, rows: np.ndarray, mode: np.ndarray, prob: np.ndarray,
        x: np.ndarray, y: np.ndarray,
    ) -> Predictions:
        return Predictions(
            t_s=obstacles.t_s, dt_s=self.c.dt_s, track_id=obstacles.track_id.take(rows),
            model=[PREDICTION_MODES[i] for i in mode.tolist()], mode_prob=prob,
            length_m=obstacles.length_m.take(rows), width_m=obstacles.width_m.take(rows),
            x_m=x, y_m=y,
        )
