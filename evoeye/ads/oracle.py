"""Oracle module substitutes for counterfactual re-simulation (`evoeye explain`).

Each implements the Protocol of the module it replaces, so it drops into an `ADS` as a public
attribute: perception = the ground truth, prediction = the actors' true futures, planning = the
ADS's own planner configured carefully, control = an ideal actuator. An oracle is allowed to
know what the real module cannot (the truth, the future); it is never a different algorithm
where a better configuration of the same one is what is asked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from evoeye.ads.config import ControlConfig, PlanningConfig, PredictionConfig
from evoeye.ads.control import PurePursuitController
from evoeye.ads.messages import (
    ControlCommand,
    Localization,
    Obstacles,
    PlannedTrajectory,
    Predictions,
)
from evoeye.ads.planning import RoutePlanner
from evoeye.scene import EGO_ID, RoadMap, SceneState


class GroundTruthPerception:
    """Every actor but the ego, exactly as it is now: no misses, no noise, no latency, and the
    track id is the actor id."""

    def perceive(self, scene: SceneState, ego: Localization) -> Obstacles:
        rows = np.flatnonzero(scene.actor_id != EGO_ID)
        h, v = scene.heading_rad[rows], scene.speed_mps[rows]
        return Obstacles(
            t_s=float(scene.t_s), track_id=scene.actor_id[rows].copy(),
            obj_class=["car"] * len(rows), x_m=scene.x_m[rows], y_m=scene.y_m[rows],
            heading_rad=h, vx_mps=v * np.cos(h), vy_mps=v * np.sin(h),
            length_m=scene.length_m[rows], width_m=scene.width_m[rows],
            confidence=np.ones(len(rows)),
        )


@dataclass(frozen=True)
class TrueFutures:
    """The ground-truth positions of every actor, frame by frame, of some run.

    Rows are frames (at t = k·dt_s), columns actors (by `actor_id`); NaN where an actor is
    absent. Past the last frame an actor moves on at its last velocity.
    """

    dt_s: float
    actor_id: np.ndarray  # (A,)
    x_m: np.ndarray  # (F, A)
    y_m: np.ndarray  # (F, A)
    vx_mps: np.ndarray  # (A,) velocity at the actor's last present frame
    vy_mps: np.ndarray  # (A,)
    last_frame: np.ndarray  # (A,) the actor's last present frame

    @classmethod
    def from_scenes(cls, scenes: list[SceneState], dt_s: float) -> TrueFutures:
        """Collect the futures of the actors (the ego excluded) of a run's scenes."""
        ids = sorted({int(a) for sc in scenes for a in sc.actor_id} - {EGO_ID})
        col = {a: i for i, a in enumerate(ids)}
        f, n = len(scenes), len(ids)
        x, y = np.full((f, n), np.nan), np.full((f, n), np.nan)
        vx, vy, last = np.zeros(n), np.zeros(n), np.zeros(n, dtype=np.int64)
        for k, sc in enumerate(scenes):
            for r, a in enumerate(sc.actor_id.tolist()):
                if a == EGO_ID:
                    continue
                c = col[a]
                x[k, c], y[k, c] = sc.x_m[r], sc.y_m[r]
                vx[c], vy[c] = sc.vx_mps[r], sc.vy_mps[r]
                last[c] = k
        return cls(dt_s, np.asarray(ids, dtype=np.int64), x, y, vx, vy, last)

    def positions(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K, A) true positions at times t_s (nearest frame; extrapolated past the end)."""
        k = np.rint(np.asarray(t_s) / self.dt_s).astype(np.int64)  # (K,)
        kc = np.minimum(k[:, None], self.last_frame[None, :])  # (K, A)
        cols = np.arange(len(self.actor_id))[None, :]
        ahead_s = (k[:, None] - kc) * self.dt_s
        return (self.x_m[kc, cols] + self.vx_mps * ahead_s,
                self.y_m[kc, cols] + self.vy_mps * ahead_s)


class TrueFuturePredictor:
    """Each perceived obstacle's future is the true future of the actor nearest to it now."""

    def __init__(self, futures: TrueFutures, config: PredictionConfig) -> None:
        self.futures = futures
        self.c = config
        self.k = int(round(config.horizon_s / config.dt_s))

    def predict(self, obstacles: Obstacles, ego: Localization) -> Predictions:
        n, f = len(obstacles.x_m), self.futures
        t = obstacles.t_s + np.arange(self.k + 1) * self.c.dt_s  # (K+1,) now, then the horizon
        # an obstacle without a present actor (a false positive) keeps its constant velocity
        x = obstacles.x_m[:, None] + obstacles.vx_mps[:, None] * (t[1:] - t[0])  # (n, K)
        y = obstacles.y_m[:, None] + obstacles.vy_mps[:, None] * (t[1:] - t[0])
        if n and len(f.actor_id):
            x_all, y_all = f.positions(t)  # (K+1, A)
            d = np.hypot(obstacles.x_m[:, None] - x_all[0], obstacles.y_m[:, None] - y_all[0])
            match = np.nan_to_num(d, nan=np.inf).argmin(axis=1)  # (n,) nearest actor now
            tx, ty = x_all[1:, match].T, y_all[1:, match].T  # (n, K)
            known = np.isfinite(tx)
            x, y = np.where(known, tx, x), np.where(known, ty, y)
        return Predictions(
            t_s=obstacles.t_s, dt_s=self.c.dt_s, track_id=obstacles.track_id,
            model=["truth"] * n, mode_prob=np.ones(n), length_m=obstacles.length_m,
            width_m=obstacles.width_m,
            x_m=np.ascontiguousarray(x), y_m=np.ascontiguousarray(y),
        )


def careful_planning(config: PlanningConfig) -> PlanningConfig:
    """The planner's configuration for a careful reference driver: long headway, positive gap
    margins, cautious arrival estimates, every plausible mode planned against and a cut-in
    taken as a leader early, earlier and firmer AEB (also for predicted crossings), yielding up
    to a firm brake."""
    return replace(
        config, mode_prob_min=0.2, cutin_horizon_s=2.0, aeb_on_predicted_crossings=True,
        time_headway_s=2.0, min_gap_m=4.0, follow_soft_headway_s=1.2,
        follow_decel_max_mps2=6.0, comfort_decel_mps2=6.0, corridor_margin_m=0.5,
        gap_margin_s=1.5, arrival_uncertainty_frac=0.2, go_accel_mps2=1.5,
        yield_decel_max_mps2=6.0, emergency_ttc_s=2.0,
        emergency_decel_mps2=max(config.emergency_decel_mps2, 8.0),
    )


def careful_planner(road_map: RoadMap, config: PlanningConfig, cruise_speed_mps: float,
                    frame_dt_s: float) -> RoutePlanner:
    """The ADS's route planner with `careful_planning` of its configuration."""
    return RoutePlanner(road_map, careful_planning(config), cruise_speed_mps, frame_dt_s)


class IdealController:
    """An actuator without lag or tracking error: the plan's speed one frame ahead is reached
    exactly (within the acceleration limits), and steering is pure pursuit without a rate
    limit."""

    def __init__(self, config: ControlConfig, dt_s: float) -> None:
        self.c = config
        self.dt_s = dt_s
        self._steer = PurePursuitController(replace(config, max_steering_rate_radps=math.inf),
                                            dt_s)

    def control(self, plan: PlannedTrajectory, ego: Localization) -> ControlCommand:
        c = self.c
        steer = self._steer.control(plan, ego).steering_rad
        v_next = float(np.interp(self.dt_s, plan.t_rel_s, plan.speed_mps))
        accel = min(max((v_next - ego.speed_mps) / self.dt_s, c.accel_min_mps2), c.accel_max_mps2)
        return ControlCommand(
            t_s=plan.t_s, throttle=accel / c.accel_max_mps2 if accel > 0.0 else 0.0,
            brake=accel / c.accel_min_mps2 if accel < 0.0 else 0.0, steering_rad=steer,
            accel_cmd_mps2=accel,
        )
