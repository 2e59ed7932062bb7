"""NPC vehicles that drive like cars: a path, a driver model, and a script that says what, not how.

An NPC moves along its `Path` in the path's Frenet frame. Longitudinally it is an IDM driver
(following the vehicle ahead in its corridor, slowing for curves along a preview speed profile,
and running its scripted braking event) whose acceleration is bounded to [−9, 3] m/s².
Laterally it keeps its lane or changes lanes along a smooth half-cosine offset profile whose
duration bounds the lateral speed and acceleration. The script — when to brake, when to change
lanes — only decides *what* happens; these dynamics decide *how fast* it can.

The ego is a highway-env kinematic bicycle driven by the ADS's command (`EgoVehicle`).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from highway_env.vehicle.kinematics import Vehicle

from evoeye.sim.path import Path

LANE_WIDTH_M = 4.0
CRASH_DECEL_MPS2 = 8.0  # a vehicle in a contact brakes to a standstill at this rate
MAX_DECEL_MPS2 = 9.0  # what the tyres give on a dry road: no car, NPC or ego, brakes harder
# a cut-in goes only into a gap the ego could still keep by braking at CUT_IN_EGO_DECEL_MPS2
# after CUT_IN_EGO_REACTION_S: gap ≥ closing·t + closing²/(2·b) (aggressive, not suicidal)
CUT_IN_EGO_REACTION_S = 1.5
CUT_IN_EGO_DECEL_MPS2 = 4.0
CATCH_UP_GAIN_PER_S = 2.0  # braking towards a lower desired speed: 2 m/s² per m/s above it
PROFILE_DECEL_SHARE = 0.6  # curves are planned for at this share of the comfortable braking,
# so that the speed tracks the profile with a small lag and the curve is entered on it


@dataclass(frozen=True)
class DriverModel:
    """How an NPC driver accelerates, follows and takes curves."""

    accel_mps2: float = 1.5  # IDM a
    comfort_decel_mps2: float = 2.5  # IDM b; also the decel planned ahead of curves
    time_headway_s: float = 1.2  # IDM T
    min_gap_m: float = 2.0  # IDM s0
    delta: float = 4.0
    max_accel_mps2: float = 3.0
    max_decel_mps2: float = MAX_DECEL_MPS2
    lat_accel_mps2: float = 3.0  # curve speed: v² · |κ| ≤ this
    crash_decel_mps2: float = CRASH_DECEL_MPS2
    reaction_s: float = 0.0  # it acts on what it saw this long ago (0: at once, as IDM does)


@dataclass(frozen=True)
class BrakeEvent:
    """Brake at `decel_mps2` from `start_s` for `duration_s` (overrides IDM if harder)."""

    start_s: float
    decel_mps2: float
    duration_s: float


@dataclass(frozen=True)
class LaneChange:
    """Move `offset_m` sideways (+ left of the path) over `duration_s`, once the NPC's bumper gap
    ahead of the ego (its rear to the ego's front, negative when behind) crosses `trigger_gap_m`
    in either direction and the target lane is clear of other NPCs."""

    offset_m: float
    duration_s: float
    trigger_gap_m: float

    def peak_lateral(self) -> tuple[float, float]:
        """(peak lateral speed m/s, peak lateral acceleration m/s²) of the offset profile."""
        w, t = abs(self.offset_m), self.duration_s
        return math.pi * w / (2.0 * t), math.pi**2 * w / (2.0 * t * t)


def cut_in_gap_m(closing_mps: float) -> float:
    """The smallest bumper gap ahead of the ego a cut-in accepts while the ego closes on it at
    closing_mps: the ego, braking at CUT_IN_EGO_DECEL_MPS2 after CUT_IN_EGO_REACTION_S, keeps
    it. At 5 m/s that is 10.6 m (2.1 s), at 10 m/s 27.5 m, at 15 m/s 50.6 m."""
    v = max(closing_mps, 0.0)
    return v * CUT_IN_EGO_REACTION_S + v * v / (2.0 * CUT_IN_EGO_DECEL_MPS2)


def curve_speed(path: Path, driver: DriverModel) -> np.ndarray:
    """(K,) the speed profile an NPC driver keeps to on `path` (curves taken within its lateral
    acceleration, braked for ahead of time)."""
    return path.speed_profile(driver.lat_accel_mps2,
                              PROFILE_DECEL_SHARE * driver.comfort_decel_mps2)


class Npc(Vehicle):
    """A scripted NPC on a path; the World decides its leader and triggers, `advance` moves it."""

    def __init__(
        self, road, path: Path, s_m: float, speed_mps: float, *, desired_speed_mps: float,
        d_m: float = 0.0, driver: DriverModel | None = None, brake: BrakeEvent | None = None,
        lane_change: LaneChange | None = None,
    ) -> None:
        x, y, h = path.pose(s_m, d_m)
        super().__init__(road, [x, y], h, speed_mps)
        self.path = path
        self.s_m = float(s_m)
        self.d_m = float(d_m)
        self.driver = driver or DriverModel()
        self.desired_speed_mps = float(desired_speed_mps)
        self.brake = brake
        self.lane_change = lane_change
        self.clock_s = 0.0  # time since the scenario started
        self.accel_mps2 = 0.0
        self.check_collisions = False  # contacts are the World's (all pairs, vectorised)
        self._lc_start_s: float | None = None  # when the lane change began
        self._lc_from_m = self.d_m
        self._trigger_side: float | None = None  # sign of (gap − trigger) when last seen
        self._armed = False  # the trigger gap was crossed; waiting for a clear target lane
        dm = self.driver
        self._curve_speed = curve_speed(path, dm).tolist()  # floats: one lookup per step
        self._idm_root = 2.0 * math.sqrt(dm.accel_mps2 * dm.comfort_decel_mps2)  # IDM's 2·√(ab)
        self._reacting: deque[float] | None = None  # the decisions not acted on yet (reaction_s)

    # -- the script ------------------------------------------------------------------------------
    @property
    def changing_lanes(self) -> bool:
        return self._lc_start_s is not None and self.clock_s < self._lc_start_s + (
            self.lane_change.duration_s
        )

    def lateral_target_m(self) -> float:
        """Where the NPC is heading laterally, relative to its current offset (0 if nowhere)."""
        if self.lane_change is None or self._lc_start_s is None:
            return 0.0
        return self._lc_from_m + self.lane_change.offset_m - self.d_m

    def wants_lane_change(self, gap_to_ego_m: float, ego_closing_mps: float) -> bool:
        """Update the trigger with the current bumper gap ahead of the ego and the speed at which
        the ego closes it; True once it fired, the gap is one the ego could still keep (see
        `cut_in_gap_m`: an aggressive driver, not a suicidal one) and the change has not started
        yet."""
        lc = self.lane_change
        if lc is None or self._lc_start_s is not None or self.crashed:
            return False
        side = math.copysign(1.0, gap_to_ego_m - lc.trigger_gap_m)
        if self._trigger_side is not None and side != self._trigger_side:
            self._armed = True
        self._trigger_side = side
        if self._armed and gap_to_ego_m < 0.0:  # fell behind the ego again: the moment passed
            self._armed = False
        return self._armed and gap_to_ego_m >= cut_in_gap_m(ego_closing_mps)

    def start_lane_change(self) -> None:
        self._lc_start_s = self.clock_s
        self._lc_from_m = self.d_m
        self._armed = False

    # -- longitudinal ----------------------------------------------------------------------------
    def longitudinal(self, gap_m: float, leader_speed_mps: float, dt: float = 0.05) -> float:
        """`decide`, acted on `driver.reaction_s` (whole steps of dt) later; until the first
        decision comes due, the NPC keeps its speed."""
        a = self.decide(gap_m, leader_speed_mps)
        if self.driver.reaction_s <= 0.0 or self.crashed:
            return a
        if self._reacting is None:
            self._reacting = deque([0.0] * round(self.driver.reaction_s / dt))
        self._reacting.append(a)
        return self._reacting.popleft()

    def decide(self, gap_m: float, leader_speed_mps: float) -> float:
        """The bounded acceleration: IDM behind the leader (gap_m bumper to bumper, inf if
        none) towards the curve-limited desired speed, and the scripted brake."""
        dm = self.driver
        v = self.speed
        if self.crashed:
            return -dm.crash_decel_mps2 if v > 0.0 else 0.0
        v0 = max(min(self.desired_speed_mps, self._curve_speed[self.path.index(self.s_m)]), 0.1)
        if v <= v0:
            a = dm.accel_mps2 * (1.0 - (v / v0) ** dm.delta)
        else:  # above the desired speed (a curve ahead, a slower set speed): comfortable braking
            a = -min(dm.comfort_decel_mps2, CATCH_UP_GAIN_PER_S * (v - v0))
        if math.isfinite(gap_m):
            closing = v - leader_speed_mps
            s_star = dm.min_gap_m + max(
                0.0, v * dm.time_headway_s
                + v * closing / self._idm_root)
            interaction = (s_star / max(gap_m, 0.1)) ** 2
            a = min(a, dm.accel_mps2 * (1.0 - (v / v0) ** dm.delta - interaction))
        b = self.brake
        if b is not None and b.start_s <= self.clock_s < b.start_s + b.duration_s:
            a = min(a, -b.decel_mps2)
        return min(max(a, -dm.max_decel_mps2), dm.max_accel_mps2)

    # -- motion ------------------------------------------------------------------------------------
    def advance(self, accel_mps2: float, dt: float) -> None:
        """Integrate dt: speed never negative, position along the path, lateral offset profile.
        A crashed NPC leaves its path: it slides on along its heading to a standstill."""
        v0 = self.speed
        v1 = max(v0 + accel_mps2 * dt, 0.0)
        self.accel_mps2 = (v1 - v0) / dt
        self.speed = v1
        self.clock_s += dt
        if self.crashed:
            step = 0.5 * (v0 + v1) * dt
            self.position[0] += step * math.cos(self.heading)
            self.position[1] += step * math.sin(self.heading)
            return
        self.s_m = min(self.s_m + 0.5 * (v0 + v1) * dt, self.path.length_m)
        d_dot = 0.0
        lc = self.lane_change
        if self._lc_start_s is not None:
            tau = min((self.clock_s - self._lc_start_s) / lc.duration_s, 1.0)
            self.d_m = self._lc_from_m + lc.offset_m * 0.5 * (1.0 - math.cos(math.pi * tau))
            if tau < 1.0:
                d_dot = lc.offset_m * math.pi / (2.0 * lc.duration_s) * math.sin(math.pi * tau)
        x, y, h = self.path.pose(self.s_m, self.d_m)
        self.position[0], self.position[1] = x, y
        self.heading = h + math.atan2(d_dot, max(v1, 1.0))

    def act(self, action=None) -> None:  # the World drives NPCs; highway-env must not
        return

    def step(self, dt: float) -> None:
        return

    def on_state_update(self) -> None:
        return


class EgoVehicle(Vehicle):
    """The ego: a kinematic bicycle driven by the ADS's control command.

    It never needs highway-env's lane bookkeeping (the ADS has its own map), so the per-step
    closest-lane search is skipped.
    """

    def on_state_update(self) -> None:
        return

    def clip_actions(self) -> None:
        """After a contact the ego brakes to a standstill like a crashed NPC (highway-env's own
        rule, accel = −speed, would let it roll on through what it hit for seconds); it never
        brakes harder than the tyres give (the ADS's controller saturates at 8 m/s² anyway)."""
        super().clip_actions()
        if self.crashed:
            self.action["acceleration"] = -CRASH_DECEL_MPS2 if self.speed > 0.0 else 0.0
        elif self.action["acceleration"] < -MAX_DECEL_MPS2:
            self.action["acceleration"] = -MAX_DECEL_MPS2

    def step(self, dt: float) -> None:
        super().step(dt)
        if self.speed < 0.0:  # braking stops a vehicle; it never drives it backwards
            self.speed = 0.0
