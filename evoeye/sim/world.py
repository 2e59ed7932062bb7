"""The simulated world: the ego and NPCs on a highway-env road, stepped by us at 20 Hz.

Every actor exists from t = 0. Each step: the ego takes the ADS's command (highway-env's
kinematic bicycle), every NPC finds the vehicle ahead in its corridor and fires its script's
triggers on relative state (`traffic.py`), the NPCs move along their paths with bounded
dynamics (`npc.py`), and contacts are checked for every pair of vehicles: a contact marks both
as crashed (recorded in the ground truth) and a crashed vehicle brakes to a standstill, so no
two vehicles ever pass through each other. We do not call `env.step` (observation and
rendering work per step: ~140 steps/s for 7 vehicles, against ~1100 stepping the road directly)
nor `road.step` (its pairwise checks are per-pair Python); the road network and the ego's
dynamics are highway-env's.
"""

from __future__ import annotations

import numpy as np
from highway_env.road.road import Road

from evoeye.boxes import box_corners, box_gap_bound, box_gaps
from evoeye.scene import EGO_ID, RoadMap, SceneState
from evoeye.sim.npc import EgoVehicle, Npc
from evoeye.sim.path import Path
from evoeye.sim.traffic import (
    Conflict,
    Relations,
    YieldToEgo,
    clear_to_change,
    half_sums,
    leaders,
    may_curve,
    path_block,
)

NPC_REACTION_S = 1.0  # an NPC driver brakes for a car crossing its way after this long
# a pair whose footprint gap bound exceeds this cannot touch: far above the rounding of the bound
CONTACT_SLACK_M = 1e-6


class World:
    """Ego + NPCs; `scene()` reads it, `step()` advances it by dt."""

    def __init__(self, road: Road, ego: EgoVehicle, npcs: list[Npc], road_map: RoadMap,
                 conflicts: list[Conflict] | None = None, yields: list[YieldToEgo] | None = None,
                 ego_path: Path | None = None, occluders: np.ndarray | None = None):
        self.road = road
        self.occluders = occluders  # (K, 4) buildings: they block sight, not motion
        self.conflicts = conflicts or []
        self.yields = yields or []
        self.ego_path = ego_path  # the ego's route, to time it to crossings NPCs yield at
        self._ego_s = ego_path.project(*ego.position)[0] if ego_path is not None else 0.0
        self.road_map = road_map
        self.t_s = 0.0
        self.ego = ego
        self.npcs = npcs
        self.vehicles = [ego, *npcs]
        road.vehicles[:] = self.vehicles
        self.actor_id = np.arange(len(self.vehicles), dtype=np.int64)  # ego = EGO_ID = 0
        self.length_m = np.array([v.LENGTH for v in self.vehicles], dtype=float)
        self.width_m = np.array([v.WIDTH for v in self.vehicles], dtype=float)
        self.crashed = np.zeros(len(self.vehicles), dtype=bool)
        self.collision_actor = -1
        self._accel = np.zeros(len(self.vehicles))
        self._blocked_s = np.zeros(len(self.vehicles))  # how long a crossing car has blocked each
        # every pair (i < j) and the distance within which their circumscribed circles meet
        self._pair_i, self._pair_j = np.triu_indices(len(self.vehicles), k=1)
        reach = 0.5 * np.hypot(self.length_m, self.width_m)  # (n,) circumscribed radius
        self._pair_reach_m = reach[self._pair_i] + reach[self._pair_j]
        self._half_sums = half_sums(self.length_m, self.width_m)
        # the NPCs whose path turns somewhere: only they can be blocked along an arc
        self._on_curves = [(i, npc) for i, npc in enumerate(npcs, start=1) if may_curve(npc.path)]
        # the NPCs with a scripted lane change: only they have a trigger to update
        self._scripted = [(i, npc) for i, npc in enumerate(npcs, start=1)
                          if npc.lane_change is not None]
        assert EGO_ID == 0

    # -- reading -------------------------------------------------------------------------------
    def _state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        vs = self.vehicles
        x, y = np.array([v.position for v in vs], dtype=float).T.copy()  # contiguous rows
        heading = np.array([v.heading for v in vs], dtype=float)
        speed = np.array([v.speed for v in vs], dtype=float)
        return x, y, heading, speed

    def scene(self) -> SceneState:
        """Ground truth now. Acceleration is the one applied over the last step."""
        x, y, heading, speed = self._state()
        return SceneState(
            t_s=self.t_s, actor_id=self.actor_id.copy(), x_m=x, y_m=y, heading_rad=heading,
            speed_mps=speed, accel_mps2=self._accel.copy(), length_m=self.length_m.copy(),
            width_m=self.width_m.copy(), crashed=self.crashed.copy(),
            ego_collision=bool(self.crashed[0]), collision_actor=self.collision_actor,
            occluders=self.occluders,
        )

    # -- advancing -----------------------------------------------------------------------------
    def step(self, accel_mps2: float, steering_rad: float, dt: float) -> None:
        """Apply the ego command, let the NPCs decide and move, integrate dt, check contacts.
        In phases that `lockstep_world.step_worlds` also calls, doing the array ones for many
        worlds at once."""
        x, y, heading, speed = self._state()
        rel = Relations.of(x, y, heading, speed, *self._half_sums)
        gap, v_lead, block = leaders(rel, np.array(self._lateral_targets()))
        self._block_along_paths(block, x, y, heading)
        gap, v_lead, self._blocked_s = answer_blocks(gap, v_lead, block, self._blocked_s, dt)
        self._wait_at_crossings(gap, v_lead)
        self._lane_changes(rel, speed)
        accels = self._decide(gap.tolist(), v_lead.tolist(), dt)
        self._accel = np.array(self._advance(accel_mps2, steering_rad, accels, dt))
        self._contacts()

    def _lateral_targets(self) -> list[float]:
        """Each row's lateral target (0 for the ego), the shift `leaders` looks for leaders at."""
        return [0.0] + [n.lateral_target_m() for n in self.npcs]

    def _lane_changes(self, rel: Relations, speed: np.ndarray) -> None:
        """Update the scripted lane changes' triggers (on floats) and start those that fire."""
        if not self._scripted:
            return
        v, cos_dh = speed.tolist(), rel.cos_dh[0].tolist()
        for i, npc in self._scripted:
            closing = v[0] - v[i] * cos_dh[i]
            if npc.wants_lane_change(rel.gap_ahead_of(i, 0), closing) and clear_to_change(
                rel, i, npc.lane_change.offset_m
            ):
                npc.start_lane_change()

    def _decide(self, gaps: list[float], v_leads: list[float], dt: float) -> list[float]:
        """Every NPC's acceleration from its gap and leader speed (floats for the scalar driver
        models; row 0, the ego's, is not read)."""
        return [npc.longitudinal(gaps[i], v_leads[i], dt)
                for i, npc in enumerate(self.npcs, start=1)]

    def _advance(self, accel_mps2: float, steering_rad: float, accels: list[float],
                 dt: float) -> list[float]:
        """Move the ego (highway-env's bicycle) and the NPCs by dt; the accelerations applied."""
        ego = self.ego
        v_before = ego.speed
        ego.action = {"acceleration": float(accel_mps2), "steering": float(steering_rad)}
        ego.crashed = bool(self.crashed[0])
        ego.step(dt)
        for npc, a in zip(self.npcs, accels, strict=True):
            npc.advance(a, dt)
        self.t_s += dt
        return [(ego.speed - v_before) / dt] + [n.accel_mps2 for n in self.npcs]

    def _block_along_paths(self, block: np.ndarray, x: np.ndarray, y: np.ndarray,
                           heading: np.ndarray) -> None:
        """Where an NPC's path curves ahead (a turn), what blocks it is looked for along the
        arc rather than straight ahead: a car standing in the turn is seen as a driver sees it."""
        half_l, half_w = 0.5 * self.length_m, 0.5 * self.width_m
        for i, npc in self._on_curves:
            if npc.crashed or npc.changing_lanes:
                continue
            g = path_block(npc.path, npc.s_m, half_l[i], half_w[i], x, y, heading, half_l,
                           half_w, i)
            if g < block[i]:
                block[i] = g

    def _wait_at_crossings(self, gap: np.ndarray, v_lead: np.ndarray) -> None:
        """An NPC waiting at a crossing (for another NPC, or yielding to the ego) sees a
        standing car at its stop point."""
        if not (self.conflicts or self.yields):
            return
        s = {i: npc.s_m for i, npc in enumerate(self.npcs, start=1)}
        v = {i: npc.speed for i, npc in enumerate(self.npcs, start=1)}
        waits = [c.wait_gap(s, v) for c in self.conflicts]
        live = [y for y in self.yields if not y.settled(s[y.i])]
        if live:  # the ego's place on its route is needed (and followed) only for these
            self._ego_s = self.ego_path.project(*self.ego.position, near_s=self._ego_s)[0]
            waits += [(y.i, y.wait_gap(s[y.i], v[y.i], self._ego_s, self.ego.speed))
                      for y in live]
        for wait in waits:
            if wait is not None and wait[1] is not None and wait[1] < gap[wait[0]]:
                gap[wait[0]], v_lead[wait[0]] = max(wait[1], 0.0), 0.0

    def _contacts(self) -> None:
        """Mark every overlapping pair of footprints as crashed; remember the ego's partner."""
        x, y, heading, _ = self._state()
        i, j = self._pair_i, self._pair_j
        close = np.hypot(x[i] - x[j], y[i] - y[j]) <= self._pair_reach_m
        if not np.count_nonzero(close):
            return
        i, j = i[close], j[close]
        length, width = self.length_m, self.width_m
        bound = box_gap_bound(x[i], y[i], heading[i], length[i], width[i], x[j], y[j],
                              heading[j], length[j], width[j])
        near = bound <= CONTACT_SLACK_M  # usually none: most close pairs are lanes apart
        if not np.count_nonzero(near):
            return
        i, j = i[near], j[near]
        corners = box_corners(x, y, heading, length, width)
        touching = box_gaps(corners[i], corners[j]) <= 0.0
        if np.count_nonzero(touching):
            self._crash(i[touching], j[touching], x, y)

    def _crash(self, i: np.ndarray, j: np.ndarray, x: np.ndarray, y: np.ndarray) -> None:
        """Pairs (i, j) (i < j) touch, at positions x, y: both crashed, the ego's partner (the
        nearest, if several) remembered at its first contact."""
        if not self.crashed[0] and np.count_nonzero(i == 0):
            partners = j[i == 0]
            d = np.hypot(x[partners] - x[0], y[partners] - y[0])
            self.collision_actor = int(self.actor_id[partners[int(np.argmin(d))]])
        self.crashed[i] = True
        self.crashed[j] = True
        for k in np.concatenate((i, j)).tolist():
            self.vehicles[k].crashed = True


def answer_blocks(gap: np.ndarray, v_lead: np.ndarray, block: np.ndarray,
                  blocked_s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(gap, leader speed, blocked time) once each driver answers a crossing car that has blocked
    its way for longer than `NPC_REACTION_S` as a standing leader. Elementwise: any shape."""
    blocked_s = np.where(np.isfinite(block), blocked_s + dt, 0.0)
    answered = (blocked_s > NPC_REACTION_S) & (block < gap)  # seen after a reaction time
    return np.where(answered, block, gap), np.where(answered, 0.0, v_lead), blocked_s
