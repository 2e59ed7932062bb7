"""Scripted NPC behaviours on top of highway-env's IDM vehicles.

NPCs drive with highway-env's IDM (longitudinal) and lane-keeping steering; MOBIL's own lane
changes are off so that every manoeuvre is a deterministic function of the scenario parameters.
Scripts add what a logical scenario varies: braking events, timed or position-triggered lane
changes with a given sharpness.
"""

from __future__ import annotations

from dataclasses import dataclass

from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.kinematics import Vehicle


@dataclass(frozen=True)
class BrakeEvent:
    """Brake at `decel_mps2` from `start_s` for `duration_s` (overrides IDM if harder)."""

    start_s: float
    decel_mps2: float
    duration_s: float


@dataclass(frozen=True)
class LaneChange:
    """Change into lane `to_lane` once after `start_s`, when the NPC's centre is between
    `ahead_min_m` and `ahead_max_m` ahead of the ego's centre (the trigger window)."""

    to_lane: int
    duration_s: float  # time to complete the lateral move; lower is sharper
    start_s: float = 0.0
    ahead_min_m: float = -float("inf")
    ahead_max_m: float = float("inf")


class ScriptedVehicle(IDMVehicle):
    """An IDM vehicle that follows its route and runs its scripted events."""

    def __init__(
        self,
        road,
        position,
        heading: float = 0.0,
        speed: float = 0.0,
        *,
        target_speed: float,
        route=None,
        target_lane_index=None,
        brake: BrakeEvent | None = None,
        lane_change: LaneChange | None = None,
        ego: Vehicle | None = None,
    ) -> None:
        super().__init__(
            road,
            position,
            heading=heading,
            speed=speed,
            target_lane_index=target_lane_index,
            target_speed=target_speed,
            route=route,
            enable_lane_change=False,
            timer=0.0,
        )
        # NPCs are scripted actors: contacts among them are not simulated (highway-env checks a
        # pair only if one side checks), so a parameter means what it says; the ego checks all.
        self.check_collisions = False
        self.brake = brake
        self.lane_change = lane_change
        self.ego = ego
        self.clock_s = 0.0  # time since the scenario started (not since spawn)
        self._lane_change_done = False

    def act(self, action=None) -> None:
        if self.crashed:
            return
        self._maybe_change_lane()
        super().act()
        b = self.brake
        if b is not None and b.start_s <= self.clock_s < b.start_s + b.duration_s:
            self.action["acceleration"] = min(self.action["acceleration"], -b.decel_mps2)

    def step(self, dt: float) -> None:
        self.clock_s += dt
        super().step(dt)
        _no_reverse(self)

    def _maybe_change_lane(self) -> None:
        lc = self.lane_change
        if lc is None or self._lane_change_done or self.clock_s < lc.start_s:
            return
        if self.ego is not None:
            ahead_m = self.position[0] - self.ego.position[0]
            if not lc.ahead_min_m <= ahead_m <= lc.ahead_max_m:
                return
        _from, _to, _ = self.lane_index
        self.target_lane_index = (_from, _to, lc.to_lane)
        # highway-env's lateral loop is first order with gain KP_LATERAL: ~95 % of the move in
        # 3 / KP_LATERAL seconds, so the duration sets the gain (per vehicle, not per class).
        self.KP_LATERAL = 3.0 / lc.duration_s
        self._lane_change_done = True

    def on_state_update(self) -> None:
        # highway-env scans every lane of the network for the closest one; a scripted NPC is
        # only ever on its current or its target lane (the next route lane once past a lane's
        # end), so look there: 2 lanes instead of 21 at the intersection.
        if self.road is None:
            return
        net = self.road.network
        candidates = {self.lane_index, self.target_lane_index}
        best, best_d = None, float("inf")
        for idx in candidates:
            if idx is None or idx[2] is None:
                continue
            d = net.get_lane(idx).distance_with_heading(self.position, self.heading, 0.2)
            if d < best_d:
                best, best_d = idx, d
        if best is None:
            super().on_state_update()
            return
        self.lane_index = best
        self.lane = net.get_lane(best)


class EgoVehicle(Vehicle):
    """The ego: a kinematic bicycle driven by the ADS's control command.

    It never needs highway-env's lane bookkeeping (the ADS has its own map), so the per-step
    closest-lane search is skipped.
    """

    def on_state_update(self) -> None:
        return

    def step(self, dt: float) -> None:
        super().step(dt)
        _no_reverse(self)


def _no_reverse(vehicle: Vehicle) -> None:
    """Braking stops a vehicle; it never drives it backwards (highway-env's model would)."""
    if vehicle.speed < 0.0:
        vehicle.speed = 0.0
