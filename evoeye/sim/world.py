"""The simulated world: a highway-env Road with the ego and scripted NPCs, stepped directly.

We drive `road.act(); road.step(dt)` ourselves instead of `env.step` (no observation or
rendering work per step: ~8× faster, DESIGN.md §5). Collisions are highway-env's own checks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from highway_env.road.road import Road

from evoeye.scene import EGO_ID, RoadMap, SceneState
from evoeye.sim.npc import EgoVehicle

SPAWN_CLEARANCE_M = 8.0  # an NPC is not spawned closer than this to a vehicle in its lane …
SAME_LANE_M = 2.5  # … i.e. one less than this far to its side


@dataclass
class Actor:
    """A vehicle with a stable actor id, present in the world from `spawn_s` on."""

    actor_id: int
    vehicle: object  # a highway-env Vehicle
    spawn_s: float = 0.0
    prev_speed_mps: float = field(default=0.0, init=False)


class World:
    """Ego + NPCs on a highway-env road; `scene()` reads it, `step()` advances it by dt."""

    def __init__(self, road: Road, ego: EgoVehicle, npcs: list[Actor], road_map: RoadMap):
        self.road = road
        self.road_map = road_map
        self.t_s = 0.0
        self.ego = Actor(EGO_ID, ego)
        self.ego.prev_speed_mps = ego.speed
        self._pending = sorted(npcs, key=lambda a: (a.spawn_s, a.actor_id))
        self.active: list[Actor] = [self.ego]
        road.vehicles[:] = [ego]
        self.collision_actor = -1
        self._accel = np.zeros(1)
        self._spawn_due()

    # -- reading -------------------------------------------------------------------------------
    def scene(self) -> SceneState:
        """Ground truth now. Acceleration is the finite difference over the last step."""
        vs = [a.vehicle for a in self.active]
        pos = np.array([v.position for v in vs])
        return SceneState(
            t_s=self.t_s,
            actor_id=np.array([a.actor_id for a in self.active], dtype=np.int64),
            x_m=pos[:, 0].copy(),
            y_m=pos[:, 1].copy(),
            heading_rad=np.array([v.heading for v in vs]),
            speed_mps=np.array([v.speed for v in vs]),
            accel_mps2=self._accel.copy(),
            length_m=np.array([v.LENGTH for v in vs]),
            width_m=np.array([v.WIDTH for v in vs]),
            crashed=np.array([v.crashed for v in vs]),
            ego_collision=bool(self.ego.vehicle.crashed),
            collision_actor=self.collision_actor,
        )

    # -- advancing -----------------------------------------------------------------------------
    def step(self, accel_mps2: float, steering_rad: float, dt: float) -> None:
        """Apply the ego command, let NPCs act, integrate dt, check collisions, spawn NPCs."""
        ego = self.ego.vehicle
        was_crashed = ego.crashed
        ego.action = {"acceleration": float(accel_mps2), "steering": float(steering_rad)}
        for a in self.active:
            a.prev_speed_mps = a.vehicle.speed
        self.road.act()  # NPC behaviours decide; the ego keeps the action set above
        self.road.step(dt)
        self.t_s += dt
        if ego.crashed and not was_crashed:
            self.collision_actor = self._partner()
        self._accel = np.array(
            [(a.vehicle.speed - a.prev_speed_mps) / dt for a in self.active]
        )
        self._spawn_due()

    def _spawn_due(self) -> None:
        """Add NPCs whose time has come; one whose spawn point is occupied waits until clear."""
        for actor in list(self._pending):
            if actor.spawn_s > self.t_s + 1e-9:
                break
            if self._occupied(actor.vehicle):
                continue
            self._pending.remove(actor)
            actor.prev_speed_mps = actor.vehicle.speed
            self.active.append(actor)
            self.road.vehicles.append(actor.vehicle)
            self._accel = np.append(self._accel, 0.0)

    def _occupied(self, vehicle) -> bool:
        """Another vehicle within SPAWN_CLEARANCE_M ahead or behind, in the same lane."""
        c, s = np.cos(vehicle.heading), np.sin(vehicle.heading)
        for a in self.active:
            dx, dy = a.vehicle.position - vehicle.position
            if abs(c * dx + s * dy) < SPAWN_CLEARANCE_M and abs(c * dy - s * dx) < SAME_LANE_M:
                return True
        return False

    def _partner(self) -> int:
        """The crashed NPC nearest the ego: who the ego collided with."""
        ego_pos = self.ego.vehicle.position
        best, best_d = -1, float("inf")
        for a in self.active[1:]:
            if a.vehicle.crashed:
                d = float(np.hypot(*(a.vehicle.position - ego_pos)))
                if d < best_d:
                    best, best_d = a.actor_id, d
        return best
