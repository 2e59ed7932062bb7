"""`occluded-crossing` (S3): a street, cars parked along one kerb, three crossing pedestrians.

The road is a highway-env straight road of two lanes: the ego's (y = 0) and a parking lane
(y = 4) whose parked cars are sight-blocking boxes (`SceneState.occluders`, as the
intersection's buildings): they hide what is behind them from the ADS's sensors, not from the
ground truth, and nothing drives into them. Pedestrians are NPCs (`Npc`) of a pedestrian's
size and pace on paths of their own across the street; every one exists from t = 0, far from
the ego, and is timed like the intersection's NPCs: placed so that, walking without a stop, it
reaches the ego's lane centre `<name>_offset_s` after the ego would at its set speed.

* `hidden_ped` comes from the parked side and steps out through a gap between two parked
  cars: the ADS sees it only once it is clear of them (perception's share).
* `kerb_ped` waits at the open kerb (`KerbWait`) and steps off once the ego is within
  `kerb_ped_go_s` of its crossing (a driver who waits for it waits in vain: it waits for the
  car to pass, and goes only when the car is close): standing, it is predicted to stay
  (prediction's share); it goes when the ego is close enough that yielding takes firm braking
  (planning's share).
* `turn_ped` walks along the open pavement the ego's way and turns across at its crossing: a
  turn no constant-velocity or lane-based prediction foresees.

A pedestrian who sees the ego crossing its way right in front of it stops, as any NPC does
(`traffic.leaders`, after `NPC_REACTION_S`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from highway_env.road.road import Road, RoadNetwork

from evoeye.scene import RoadMap
from evoeye.sim.intersection import start_for_arrival
from evoeye.sim.npc import DriverModel, EgoVehicle, Npc
from evoeye.sim.path import Path
from evoeye.sim.roadmap import road_map_from_network
from evoeye.sim.traffic import PASSED_M
from evoeye.sim.world import World

ROAD_LENGTH_M = 500.0
SPEED_LIMIT_MPS = 14.0  # 50 km/h
EGO_START_X_M = 50.0
# the parking lane: cars along the kerb side of lane 1 (centre y = 4), sight-blocking boxes
PARKED_Y_M = 4.0  # centre line of the parked cars (1.05 m of clearance to the ego's lane)
PARKED_LENGTH_M, PARKED_WIDTH_M = 4.6, 1.9
PARKED_FROM_M, PARKED_TO_M = EGO_START_X_M - 20.0, EGO_START_X_M + 300.0
PARKED_JITTER_M = 0.6  # each gap is parked_gap_m plus up to this much (seeded)
CROSSING_GAP_M = 1.6  # the gap between parked cars where a pedestrian crosses
# pedestrians: a 0.6 m square, a walker's pace and its gentle starts and stops
PED_LENGTH_M = PED_WIDTH_M = 0.6
PEDESTRIAN = DriverModel(accel_mps2=1.0, comfort_decel_mps2=1.5, time_headway_s=1.0,
                         min_gap_m=0.5, max_accel_mps2=1.5, max_decel_mps2=3.0)
PAVEMENT_Y_M = {"open": -4.5, "parked": 8.0}  # pavement centre lines either side
FAR_M = 60.0  # crossing paths start and end this far from the ego's lane
KERB_WAIT_Y_M = -2.6  # the waiting pedestrian's centre at the open kerb (lane edge at −2 m)
TURN_RADIUS_M = 1.5  # the turning pedestrian's corner
TURN_RUN_M = 120.0  # … and the pavement it walks before it


@dataclass
class KerbWait:
    """A pedestrian (world row i) who waits at the kerb, its centre at `stop_i` on its path,
    until the ego is at most `go_s` from the crossing (`s_ego` on the ego's path), then crosses
    without looking again. The World treats it as a `YieldToEgo` (the same two calls)."""

    i: int
    stop_i: float
    s_ego: float
    go_s: float
    going: bool = field(default=False)

    def settled(self, s: float) -> bool:
        return self.going or s > self.stop_i

    def wait_gap(self, s: float, v: float, s_ego: float, v_ego: float) -> float | None:
        """Its distance to the kerb while it waits; None once it goes."""
        if self.settled(s):
            return None
        to_ego = self.s_ego - s_ego
        if to_ego < -PASSED_M or to_ego <= self.go_s * v_ego:
            self.going = True
            return None
        return self.stop_i - s


@functools.cache
def _network() -> tuple[RoadNetwork, RoadMap, Path]:
    """The street, its map and the ego's path, built once per process."""
    net = RoadNetwork.straight_road_network(lanes=2, length=ROAD_LENGTH_M,
                                            speed_limit=SPEED_LIMIT_MPS)
    ego_path = Path.from_lanes([net.get_lane(("0", "1", 0))])
    return net, road_map_from_network("occluded-crossing", net, [("0", "1", 0)]), ego_path


def _across(x_m: float, from_y_m: float) -> Path:
    """A straight crossing at x from `from_y_m` over to the other side, as far again."""
    return Path(np.array([[x_m, from_y_m], [x_m, -from_y_m]]))


def _turn(x_m: float) -> Path:
    """Along the open pavement the ego's way, a left turn at x and straight across."""
    y0, r = PAVEMENT_Y_M["open"], TURN_RADIUS_M
    a = np.linspace(-0.5 * math.pi, 0.0, 13)  # quarter circle about (x − r, y0 + r)
    corner = np.stack((x_m - r + r * np.cos(a), y0 + r + r * np.sin(a)), axis=1)
    return Path(np.concatenate(([[x_m - r - TURN_RUN_M, y0]], corner, [[x_m, FAR_M]])))


def _s_at_y(path: Path, y_m: float) -> float:
    """Arc length where a crossing path passes y_m (its last sample before it)."""
    k = int(np.flatnonzero(np.sign(path.y - y_m) != np.sign(path.y[-1] - y_m))[-1])
    return float(path.s[k])


def parked_cars(crossings_x_m: list[float], gap_m: float,
                rng: np.random.Generator) -> np.ndarray:
    """(K, 4) boxes [x_min, y_min, x_max, y_max] of the cars parked along the kerb: filled
    backwards from each crossing's gap, so a car's front bumper stands at the edge of every
    gap a pedestrian steps out of."""
    edges = sorted(crossings_x_m)
    segments, lo = [], PARKED_FROM_M
    for x in edges:
        segments.append((lo, x - 0.5 * CROSSING_GAP_M))
        lo = x + 0.5 * CROSSING_GAP_M
    segments.append((lo, PARKED_TO_M))
    boxes = []
    for a, b in segments:
        front = b
        while front - PARKED_LENGTH_M >= a:
            boxes.append([front - PARKED_LENGTH_M, PARKED_Y_M - 0.5 * PARKED_WIDTH_M, front,
                          PARKED_Y_M + 0.5 * PARKED_WIDTH_M])
            front -= PARKED_LENGTH_M + gap_m + float(rng.uniform(0.0, PARKED_JITTER_M))
    return np.array(boxes, dtype=float).reshape(-1, 4)


def _pedestrian(road: Road, path: Path, speed: float, s_conflict: float,
                t_arrive_s: float) -> Npc:
    s0 = start_for_arrival(path, speed, s_conflict, t_arrive_s, PEDESTRIAN)
    ped = Npc(road, path, s0, speed, desired_speed_mps=speed, driver=PEDESTRIAN)
    ped.LENGTH, ped.WIDTH = PED_LENGTH_M, PED_WIDTH_M
    ped.diagonal = math.hypot(PED_LENGTH_M, PED_WIDTH_M)
    return ped


def build_crossing(p: dict[str, float], rng: np.random.Generator) -> tuple[World, float]:
    """The world for one concrete scenario, and the ego's cruise speed."""
    net, road_map, ego_path = _network()
    road = Road(network=net, np_random=rng, record_history=False)
    v_ego = p["ego_speed_mps"]
    ego = EgoVehicle(road, [EGO_START_X_M, 0.0], 0.0, v_ego)
    x = {n: EGO_START_X_M + p[f"{n}_ahead_m"] for n in ("hidden_ped", "kerb_ped", "turn_ped")}
    paths = {"hidden_ped": _across(x["hidden_ped"], FAR_M),
             "kerb_ped": _across(x["kerb_ped"], -FAR_M), "turn_ped": _turn(x["turn_ped"])}
    npcs = [_pedestrian(road, paths[n], p[f"{n}_speed_mps"], _s_at_y(paths[n], 0.0),
                        p[f"{n}_ahead_m"] / v_ego + p[f"{n}_offset_s"]) for n in paths]
    kerb_row = 1 + list(paths).index("kerb_ped")
    wait = KerbWait(kerb_row, _s_at_y(paths["kerb_ped"], KERB_WAIT_Y_M),
                    ego_path.project(x["kerb_ped"], 0.0)[0], p["kerb_ped_go_s"])
    parked = parked_cars(list(x.values()), p["parked_gap_m"], rng)
    return World(road, ego, npcs, road_map, yields=[wait], ego_path=ego_path,
                 occluders=parked), v_ego
