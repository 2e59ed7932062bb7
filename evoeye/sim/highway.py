"""`highway-cut-in` (S1): a three-lane highway, the ego in the middle lane, six scripted NPCs.

Every NPC exists from t = 0 and drives with bounded dynamics (`npc.py`). Placements are not
critical unless the parameters make them so: the lead starts at the ego's speed and drifts to
its own desired speed; cut-ins and the overtaker fire on the bumper gap to the ego *crossing*
their trigger gap (from ahead or from behind), so the critical moment comes when the relative
motion brings it, not at a fixed time.
"""

from __future__ import annotations

import functools

import numpy as np
from highway_env.road.road import Road, RoadNetwork

from evoeye.scene import RoadMap
from evoeye.sim.npc import LANE_WIDTH_M, BrakeEvent, DriverModel, EgoVehicle, LaneChange, Npc
from evoeye.sim.path import Path
from evoeye.sim.roadmap import road_map_from_network
from evoeye.sim.world import World

N_LANES = 3
ROAD_LENGTH_M = 1400.0
EGO_LANE = 1  # lanes: 0 left (fast), 1 middle, 2 right
EGO_START_X_M = 200.0
MIN_SPACING_M = 9.0  # centre spacing enforced between NPCs placed in one lane …
PLACEMENT_DECEL_MPS2 = 3.0  # … plus what a faster car behind needs to slow at this rate
OVERTAKER_CUT_BACK_M = 12.0  # the overtaker returns to the ego lane at this bumper gap ahead
OVERTAKER_LANE_CHANGE_S = 3.5


def _spacing_m(v_behind: float, v_ahead: float) -> float:
    """Centre spacing that leaves the car behind a comfortable stop for a slower one ahead."""
    return MIN_SPACING_M + max(v_behind - v_ahead, 0.0) ** 2 / (2.0 * PLACEMENT_DECEL_MPS2)


def _place(wanted: list[tuple[int, float, float]], ego_speed: float) -> list[float]:
    """Resolve placements (lane, x, speed): in each lane, a later NPC too close to an earlier one
    (or to the ego) moves back behind it, by a spacing that grows with its closing speed."""
    placed: list[tuple[int, float, float]] = [(EGO_LANE, EGO_START_X_M, ego_speed)]
    out = []
    for lane, x, v in wanted:
        for _ in range(len(placed) + 1):
            clash = [(px, pv) for pl, px, pv in placed
                     if pl == lane and -_spacing_m(pv, v) < px - x < _spacing_m(v, pv)]
            if not clash:
                break
            px, pv = min(clash)
            x = px - _spacing_m(v, pv)
        placed.append((lane, x, v))
        out.append(x)
    return out


def _cut_in(p: dict[str, float], side: str, from_lane: int) -> LaneChange:
    return LaneChange(
        offset_m=(EGO_LANE - from_lane) * LANE_WIDTH_M, duration_s=p[f"{side}_cutin_duration_s"],
        trigger_gap_m=p[f"{side}_cutin_trigger_gap_m"],
    )


@functools.cache
def _network() -> tuple[RoadNetwork, RoadMap, tuple[Path, ...]]:
    """The static road, its map and one path per lane, built once per process."""
    net = RoadNetwork.straight_road_network(lanes=N_LANES, length=ROAD_LENGTH_M, speed_limit=40)
    paths = tuple(Path.from_lanes([net.get_lane(("0", "1", i))]) for i in range(N_LANES))
    return net, road_map_from_network("highway-cut-in", net, [("0", "1", EGO_LANE)]), paths


def build_highway(p: dict[str, float], rng: np.random.Generator) -> tuple[World, float]:
    """The world for one concrete scenario, and the ego's cruise speed."""
    net, road_map, paths = _network()
    road = Road(network=net, np_random=rng, record_history=False)
    ego_speed = p["ego_speed_mps"]
    ego = EgoVehicle(road, paths[EGO_LANE].pose(EGO_START_X_M)[:2], 0.0, ego_speed)
    lead_x = EGO_START_X_M + ego.LENGTH + p["lead_gap_m"]  # bumper gap, 5 m cars
    specs = [  # (lane, centre x, initial speed, desired speed, brake, lane change)
        (EGO_LANE, lead_x, ego_speed, p["lead_speed_mps"],
         BrakeEvent(p["lead_brake_time_s"], p["lead_brake_decel_mps2"],
                    p["lead_brake_duration_s"]), None),
        (0, EGO_START_X_M + p["left_cutin_gap_m"], p["left_cutin_speed_mps"],
         p["left_cutin_speed_mps"], None, _cut_in(p, "left", 0)),
        (2, EGO_START_X_M + p["right_cutin_gap_m"], p["right_cutin_speed_mps"],
         p["right_cutin_speed_mps"], None, _cut_in(p, "right", 2)),
        (0, EGO_START_X_M + p["left_follow_gap_m"], p["left_follow_speed_mps"],
         p["left_follow_speed_mps"], None, None),
        (2, EGO_START_X_M + p["right_follow_gap_m"], p["right_follow_speed_mps"],
         p["right_follow_speed_mps"], None, None),
        (0, EGO_START_X_M + p["overtaker_gap_m"], p["overtaker_speed_mps"],
         p["overtaker_speed_mps"], None,
         LaneChange((EGO_LANE - 0) * LANE_WIDTH_M, OVERTAKER_LANE_CHANGE_S, OVERTAKER_CUT_BACK_M)),
    ]
    xs = _place([(s[0], s[1], s[2]) for s in specs], ego_speed)
    npcs = [
        Npc(road, paths[lane], x, v_init, desired_speed_mps=v_want, brake=brake,
            lane_change=change)
        for (lane, _, v_init, v_want, brake, change), x in zip(specs, xs, strict=True)
    ]
    return World(road, ego, npcs, road_map), ego_speed


# The `follower` world variant (`worlds.py`): a car behind the ego in its lane, so that a
# needless hard brake can get the ego struck from behind. A driver of highway traffic as every
# NPC (IDM), at a common headway, who acts a human reaction time late.
FOLLOWER_HEADWAY_S = 1.0  # its bumper gap to the ego at the start, and its IDM time headway
FOLLOWER_REACTION_S = 1.0  # it acts on what it saw this long ago (NPC_REACTION_S: the same)
FOLLOWER_SPEED_GAIN = 1.1  # it would drive this much faster than the ego: the ego holds it up


def add_follower(world: World, p: dict[str, float], ego_speed: float) -> World:
    """The highway world with a follower behind the ego in its lane (the last actor), at the
    ego's speed, FOLLOWER_HEADWAY_S behind it."""
    _, _, paths = _network()
    x = EGO_START_X_M - world.ego.LENGTH - FOLLOWER_HEADWAY_S * ego_speed
    driver = DriverModel(time_headway_s=FOLLOWER_HEADWAY_S, reaction_s=FOLLOWER_REACTION_S)
    follower = Npc(world.road, paths[EGO_LANE], x, ego_speed,
                   desired_speed_mps=FOLLOWER_SPEED_GAIN * ego_speed, driver=driver)
    return World(world.road, world.ego, [*world.npcs, follower], world.road_map)
