"""Planning: a speed profile along the ego's route, from IDM following, gap acceptance and AEB.

Everything is decided in the route's Frenet frame (s along the route, d to its left). Predicted
obstacle points are projected onto the route; a point is *in the path* when it lies ahead of the
ego and laterally within the ego's corridor (both half-widths plus a margin). Then:

* an obstacle that enters the path aligned with the route within `cutin_horizon_s` is a leader
  candidate; the nearest one is followed with IDM;
* an obstacle that crosses the path is a conflict: the ego proceeds if, driving on, it clears the
  conflict region `gap_margin_s` before the other arrives or arrives that long after it left;
  otherwise it yields, stopping before the region (IDM towards a virtual stopped car), unless it
  can no longer stop comfortably, in which case it is committed and proceeds;
* automatic emergency braking (`emergency_decel_mps2`) when the time to collision with the
  leader, or to the start of a crossing conflict the ego can no longer yield to, is below
  `emergency_ttc_s`.

Headings of the plan are continuous along the route (not wrapped to (−π, π]).
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from evoeye.ads.config import PlanningConfig
from evoeye.ads.geometry import PolylineIndex
from evoeye.ads.messages import Localization, PlannedTrajectory, Predictions
from evoeye.ads.plan_arrays import Crossings, InPath, speed_profile
from evoeye.scene import RoadMap


class Planner(Protocol):
    """Plans the ego trajectory from the predicted obstacles."""

    def plan(self, predictions: Predictions, ego: Localization) -> PlannedTrajectory: ...


class RoutePlanner:
    """Longitudinal planning along the fixed route (no lane changes)."""

    def __init__(
        self, road_map: RoadMap, config: PlanningConfig, cruise_speed_mps: float, frame_dt_s: float
    ) -> None:
        c = config
        self.c = c
        self.cruise_mps = max(float(cruise_speed_mps), 0.1)
        self.frame_dt_s = frame_dt_s
        reach = 0.5 * c.ego_width_m + c.max_obstacle_half_length_m + c.corridor_margin_m + 0.5
        self.route = PolylineIndex.build(
            [road_map.route.points], c.route_resample_m, reach, c.grid_cell_m, 1
        )
        n = int(round(c.horizon_s / c.dt_s)) + 1
        self.t_rel = np.arange(n) * c.dt_s  # (P,)
        self._half_len = 0.5 * c.ego_length_m
        self._half_wid = 0.5 * c.ego_width_m
        self._corridor_half = self._half_wid + c.corridor_margin_m
        self._cos_aligned = math.cos(c.aligned_max_rad)
        self._sqrt_ab = math.sqrt(c.idm_accel_mps2 * c.idm_decel_mps2)
        self._plan_v: float | None = None  # speed and accel of the previous plan, for stitching
        self._plan_a = 0.0
        self._hold_id = -1  # the track the previous plan yielded or braked hard for …
        self._hold_decision = ""  # … and how
        self._clear_frames = 0  # frames since that conflict last called for it
        self._stop_s = 0.0  # route arc length of the stop point of the last yield
        self._proceeding = np.zeros(0, dtype=np.int64)  # crossing tracks the ego proceeds past

    def _idm(self, v: float, gap_m: float, dv_mps: float) -> float:
        """IDM acceleration behind a leader gap_m ahead (bumper to bumper), closing at dv_mps."""
        c = self.c
        free = 1.0 - (v / self.cruise_mps) ** c.idm_delta
        s_star = c.min_gap_m + max(0.0, v * c.time_headway_s + v * dv_mps / (2.0 * self._sqrt_ab))
        return c.idm_accel_mps2 * (free - (s_star / max(gap_m, 0.1)) ** 2)

    def _follow(self, v: float, gap_m: float, closing_mps: float) -> float:
        """IDM behind a leader. IDM alone brakes very hard for a car that cuts in at a moderate
        gap but is barely slower; so while the gap is at least min_gap + v·follow_soft_headway_s,
        braking is bounded by `follow_decel_max_mps2`, unless stopping the closing speed within
        the gap takes more."""
        c = self.c
        a = self._idm(v, gap_m, closing_mps)
        if a >= -c.follow_decel_max_mps2 or gap_m < c.min_gap_m + v * c.follow_soft_headway_s:
            return a
        need = 0.0
        if closing_mps > 0.0:
            need = closing_mps * closing_mps / (2.0 * max(gap_m - c.min_gap_m, 0.1))
        return max(a, -max(c.follow_decel_max_mps2, need))

    def _arrival_s(
        self, v: float | np.ndarray, vc: float | np.ndarray, dist_m: np.ndarray
    ) -> np.ndarray:
        """Time for the ego to cover dist_m from speed v, accelerating to vc = max(cruise, v) at
        go_accel (elementwise: v and vc may be arrays that broadcast against dist_m)."""
        a = self.c.go_accel_mps2
        t_acc = (vc - v) / a
        d_acc = 0.5 * (v + vc) * t_acc
        d = np.maximum(dist_m, 0.0)
        t_ramp = (np.sqrt(v * v + 2.0 * a * np.minimum(d, d_acc)) - v) / a
        return t_ramp + np.maximum(d - d_acc, 0.0) / vc

    def plan(self, predictions: Predictions, ego: Localization) -> PlannedTrajectory:
        # in pieces, which `evoeye.ads.lockstep.planning` calls for each run of a batch too,
        # doing the array work (_paths, _crossings, speed_profile, xy_at, heading_at) once for
        # the rows of many runs
        s_e = self._route_s(ego.x_m, ego.y_m)
        v = self._start_speed(ego.speed_mps)
        p = self._plausible(predictions)
        paths = None
        if p.x_m.shape[0] and p.x_m.shape[1] > 1:
            paths = self._paths(p.x_m, p.y_m, p.length_m, p.width_m, s_e)
        a, decision, leader, target = self._decide(p, paths, s_e, v)
        t_end, v_end = self._ramp(v, a, decision)
        speed, accel, s = speed_profile(self.t_rel, v, a, t_end, v_end, s_e)
        x, y = self.route.xy_at(s)
        return self._planned(ego, v, decision, target, leader, x, y, self.route.heading_at(s),
                             speed, accel)

    def _route_s(self, x_m: float, y_m: float) -> float:
        """The route arc length of the ego's position."""
        r = self.route
        fp = r.project_point(x_m, y_m)
        if fp is None:  # far off the route: rare, so a full search is fine
            v0 = r.nearest_vertex(x_m, y_m)
            return float(r.g[v0]) + (x_m - float(r.x[v0])) * float(r.tx[v0]) + (
                y_m - float(r.y[v0])
            ) * float(r.ty[v0])
        return fp[0]

    def _start_speed(self, speed_mps: float) -> float:
        """The speed the plan starts from."""
        v = speed_mps
        if self._plan_v is not None:  # stitch onto the previous plan while the ego follows it
            v_stitch = self._plan_v + self._plan_a * self.frame_dt_s
            if abs(v_stitch - v) <= self.c.stitch_tolerance_mps:
                v = v_stitch
        return max(v, 0.0)

    def _decide(
        self, p: Predictions, paths: InPath | None, s_e: float, v: float
    ) -> tuple[float, str, int, float]:
        """(accel, decision, leader track id, target speed), updating the decision state;
        `paths`: the predicted points in the path (None: no obstacle enters it)."""
        c = self.c
        a = self._idm(v, math.inf, 0.0)  # free road
        decision, leader, target = "cruise", -1, self.cruise_mps
        proceeding, self._proceeding = self._proceeding, self._proceeding[:0]
        if paths is not None:
            a, decision, leader, target = self._react(p, paths, s_e, v, a, proceeding)
        a, decision, leader, target = self._hold(s_e, v, a, decision, leader, target)
        if decision == "emergency_brake":  # AEB ramps up at its jerk
            a = max(min(self._plan_a, 0.0) - c.emergency_jerk_mps3 * self.frame_dt_s,
                    -c.emergency_decel_mps2)
        else:
            a = max(a, -c.comfort_decel_mps2)
        return a, decision, leader, target

    def _ramp(self, v: float, a: float, decision: str) -> tuple[float, float]:
        """(t_end, v_end): constant acceleration until t_end, when the speed reaches max(v,
        cruise) speeding up, or slowing down the cruise speed on a free road (0 otherwise);
        then constant, v_end."""
        if a > 1e-9:
            t_end = (max(v, self.cruise_mps) - v) / a
        elif a < -1e-9:
            floor = min(v, self.cruise_mps) if decision in ("cruise", "proceed") else 0.0
            t_end = (floor - v) / a
        else:
            t_end = math.inf
        return t_end, v + a * min(t_end, float(self.t_rel[-1]))

    def _planned(
        self, ego: Localization, v: float, decision: str, target: float, leader: int,
        x: np.ndarray, y: np.ndarray, heading: np.ndarray, speed: np.ndarray, accel: np.ndarray,
    ) -> PlannedTrajectory:
        """The plan's message; remembers where it starts, to stitch the next one onto it."""
        self._plan_v, self._plan_a = v, float(accel[0])
        return PlannedTrajectory(
            t_s=ego.t_s, decision=decision, target_speed_mps=float(target),
            leader_track_id=int(leader), t_rel_s=self.t_rel, x_m=x, y_m=y, heading_rad=heading,
            speed_mps=speed, accel_mps2=accel,
        )

    def _plausible(self, p: Predictions) -> Predictions:
        """The predicted modes at least `mode_prob_min` probable, and every track's best one."""
        n = len(p.track_id)
        if n < 2:
            return p
        keep = p.mode_prob >= self.c.mode_prob_min
        keep[0] = True
        keep[1:] |= p.track_id[1:] != p.track_id[:-1]  # the first row of a track is its best
        if np.count_nonzero(keep) == n:
            return p
        i = keep.nonzero()[0]
        return Predictions(
            t_s=p.t_s, dt_s=p.dt_s, track_id=p.track_id[i], model=[p.model[j] for j in i.tolist()],
            mode_prob=p.mode_prob[i], length_m=p.length_m[i], width_m=p.width_m[i],
            x_m=p.x_m[i], y_m=p.y_m[i],
        )

    def _hold(
        self, s_e: float, v: float, a: float, decision: str, leader: int, target: float
    ) -> tuple[float, str, int, float]:
        """Decision hysteresis: a yield or AEB is held until its conflict has not called for it
        for `release_frames` frames (a yield keeps stopping before the same point)."""
        c = self.c
        held, kind = self._hold_id, self._hold_decision
        if held >= 0 and (decision, leader) != (kind, held):
            self._clear_frames += 1
            if self._clear_frames < c.release_frames and decision != "emergency_brake":
                if kind == "emergency_brake":
                    a, decision, leader, target = -c.emergency_decel_mps2, kind, held, 0.0
                else:
                    to_stop_m = max(self._stop_s - s_e - self._half_len, 0.0)
                    a_yield = self._idm(v, to_stop_m + c.min_gap_m, v)
                    if a_yield < a:
                        a, decision, leader, target = a_yield, kind, held, 0.0
        else:
            self._clear_frames = 0
        if decision in ("yield", "emergency_brake"):
            if (decision, leader) != (kind, held):
                self._clear_frames = 0
            self._hold_id, self._hold_decision = leader, decision
        else:
            self._hold_id, self._hold_decision = -1, ""
        return a, decision, leader, target

    def _paths(
        self, x_m: np.ndarray, y_m: np.ndarray, length_m: np.ndarray, width_m: np.ndarray,
        s_e: float | np.ndarray,
    ) -> InPath | None:
        """The predicted points (n, K) in the route frame and in the ego's path; None if no
        obstacle enters the path. Row by row (s_e: a float, or a column (n, 1), one per row):
        a batch passes the rows of several runs at once."""
        r = self.route
        n, k = x_m.shape
        # every predicted point in the route frame: so, do (n, K) arc length and lateral offset
        # (off the grid, the sentinel vertex puts so ≈ −1e9 and |do| ≈ 1e9: never in the path)
        so, do, _, _ = r.project(x_m, y_m, r.candidates(x_m, y_m))
        # the direction of motion relative to the route at every point (to the next point; a
        # standing obstacle counts as aligned) → the half extents across and along the route.
        # Points 0 … K-2 are examined.
        ds = so[:, 1:] - so[:, :-1]  # (n, K-1)
        ds += 1e-4
        dd = do[:, 1:] - do[:, :-1]
        inv = 1.0 / np.hypot(ds, dd)
        cos_dh = ds * inv
        sin_abs = np.abs(dd) * inv
        cos_abs = np.abs(cos_dh)
        hl, hw = (0.5 * length_m)[:, None], (0.5 * width_m)[:, None]
        so, do = so[:, :-1], do[:, :-1]
        in_path = (np.abs(do) - (hl * sin_abs + hw * cos_abs) < self._corridor_half) & (so > s_e)
        k_in = in_path.argmax(axis=1)  # (n,) first point in the path
        at_in = k_in + np.arange(0, n * (k - 1), k - 1)
        enters = in_path.take(at_in)
        if not np.count_nonzero(enters):
            return None
        aligned = cos_dh.take(at_in) >= self._cos_aligned
        rear = so[:, 0] - (hl[:, 0] * cos_abs[:, 0] + hw[:, 0] * sin_abs[:, 0])
        return InPath(so, in_path, k_in, enters, aligned, enters & ~aligned, rear, hl, hw,
                      cos_abs, sin_abs)

    def _react(
        self, p: Predictions, w: InPath, s_e: float, v: float, a_free: float,
        proceeding: np.ndarray,
    ) -> tuple[float, str, int, float]:
        """(accel, decision, leader track id, target speed) given the obstacles in the path."""
        c = self.c
        dt = p.dt_s
        so, k_in, enters, aligned, rear = w.so, w.k_in, w.enters, w.aligned, w.rear
        # leader: the nearest aligned obstacle, ahead now, entering the path soon; AEB on its TTC
        decision, leader, target, a_nom = "cruise", -1, self.cruise_mps, a_free
        cand = enters & aligned & (rear > s_e) & (k_in < int(c.cutin_horizon_s / dt + 1e-9))
        if np.count_nonzero(cand):
            j = int(np.where(cand, rear, np.inf).argmin())
            gap_m = float(rear[j]) - s_e - self._half_len
            if gap_m <= c.follow_range_m:
                v_lead = float(so[j, 1] - so[j, 0]) / dt
                closing = v - v_lead
                if closing > 0.0 and gap_m <= c.emergency_ttc_s * closing:
                    return -c.emergency_decel_mps2, "emergency_brake", int(p.track_id[j]), 0.0
                a_nom = min(a_free, self._follow(v, gap_m, closing))
                decision, leader = "follow", int(p.track_id[j])
                target = min(self.cruise_mps, max(v_lead, 0.0))

        # gap acceptance for obstacles crossing the path
        if np.count_nonzero(w.cross):
            crossings = w.crossings
            if crossings is None:
                i = w.cross.nonzero()[0]
                ids = p.track_id[i]
                held = ids == self._hold_id if self._hold_id >= 0 else None
                crossings = self._crossings(w, i, ids, dt, s_e, v, max(self.cruise_mps, v),
                                            self._margin(ids, proceeding), held)
            return self._gap_acceptance(crossings, s_e, v, a_nom, decision, leader, target)
        return max(a_nom, -c.emergency_decel_mps2), decision, leader, target

    def _margin(self, ids: np.ndarray, proceeding: np.ndarray) -> float | np.ndarray:
        """The time a crossing gap must hold to spare, per crossing track `ids`: for a track the
        ego was already proceeding past, `proceed_hold_margin_s` less, so a marginal change
        does not revoke the proceed."""
        c = self.c
        if not len(proceeding):
            return c.gap_margin_s
        was = (ids[:, None] == proceeding).any(axis=1)
        return np.where(was, c.gap_margin_s - c.proceed_hold_margin_s, c.gap_margin_s)

    def _crossings(
        self, w: InPath, i: np.ndarray, ids: np.ndarray, dt: float | np.ndarray,
        s_e: float | np.ndarray, v: float | np.ndarray, vc: float | np.ndarray,
        margin: float | np.ndarray, held: np.ndarray | None,
    ) -> Crossings:
        """The conflict regions of the obstacles crossing the path (rows i of w, track ids ids)
        and which gaps the ego can take, stop before, or neither.

        The gap must hold with `margin` to spare against the other's arrival taken
        `arrival_uncertainty_frac` earlier (and its exit as much later); `held`: the rows of
        the track the last plan yielded or braked hard for (None: none). Row by row: the
        scalars of the run (prediction step dt, ego position s_e, speed v, vc = max(cruise, v))
        may be columns (m,), one per row, and w the rows of several runs, for a batch."""
        c = self.c
        ip = w.in_path[i]  # (m, K-1)
        km = ip.shape[1]  # points examined
        k0 = w.k_in[i]
        k1 = km - 1 - ip[:, ::-1].argmax(axis=1)  # last point in the path
        # the conflict region along the route: a crossing path is straight enough that its ends
        # in the corridor bound it
        rows = i * km
        lon_ext = w.hl * w.cos_abs + w.hw * w.sin_abs  # (n, K-1) half extent along the route
        so0, so1 = w.so.take(rows + k0), w.so.take(rows + k1)
        ext0, ext1 = lon_ext.take(rows + k0), lon_ext.take(rows + k1)
        s_lo = np.minimum(so0 - ext0, so1 - ext1)
        s_hi = np.maximum(so0 + ext0, so1 + ext1)
        t_in = (k0 + 0.5) * dt  # point k is at (k + 1)·dt: half a step before the first one in
        t_out = np.where(k1 == km - 1, np.inf, (k1 + 1.5) * dt)  # still in at the end: never out
        t_in_early = t_in * (1.0 - c.arrival_uncertainty_frac)
        t_out_late = t_out * (1.0 + c.arrival_uncertainty_frac)
        d_in = s_lo - s_e - self._half_len  # ego front to the conflict region
        v2, vc2 = v, vc
        if isinstance(v, np.ndarray):  # columns: the same for the exits as for the entries
            v2, vc2 = np.concatenate((v, v)), np.concatenate((vc, vc))
        te = self._arrival_s(v2, vc2, np.concatenate((d_in, s_hi - s_e + self._half_len)))
        te_in, te_out = te[: len(i)], te[len(i):]
        # the ego clears first, or arrives after the other has left; for the obstacle it was
        # already yielding to, only once that one is about to leave (no proceed/brake flapping
        # as braking itself delays the ego's arrival)
        after = te_in >= t_out_late + margin
        if held is not None:
            after = np.where(held, t_out_late <= margin, after)
        safe = (te_out + margin <= t_in_early) | after
        stoppable = (d_in > 0.0) & (v * v <= 2.0 * c.yield_decel_max_mps2 * d_in)
        # AEB: a conflict the ego can no longer yield to, overlapping within emergency_ttc_s
        urgent = ~safe & ~stoppable & (d_in > -c.ego_length_m) & (
            np.maximum(te_in, t_in) <= c.emergency_ttc_s
        )
        if not c.aeb_on_predicted_crossings:  # AEB sees a crossing car once it is in the path
            urgent &= k0 == 0
        return Crossings(ids, d_in, urgent, ~safe & stoppable)

    def _gap_acceptance(
        self, cr: Crossings, s_e: float, v: float, a_nom: float, decision: str, leader: int,
        target: float,
    ) -> tuple[float, str, int, float]:
        """Proceed, yield or brake hard for the obstacles crossing the path."""
        c = self.c
        if np.count_nonzero(cr.urgent):
            j = int(np.where(cr.urgent, cr.d_in, np.inf).argmin())
            return -c.emergency_decel_mps2, "emergency_brake", int(cr.ids[j]), 0.0
        if np.count_nonzero(cr.conflict):
            j = int(np.where(cr.conflict, cr.d_in, np.inf).argmin())
            d_stop = max(float(cr.d_in[j]) - c.stop_buffer_m, 0.0)
            a_yield = self._idm(v, d_stop + c.min_gap_m, v)  # virtual car at the stop point
            if a_yield < a_nom:
                a_nom, decision, target = a_yield, "yield", 0.0
                leader = int(cr.ids[j])
                self._stop_s = s_e + self._half_len + d_stop
        elif decision == "cruise":
            decision = "proceed"
            self._proceeding = cr.ids
        return max(a_nom, -c.emergency_decel_mps2), decision, leader, target
