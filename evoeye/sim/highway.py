"""`highway-cut-in` (S1): a three-lane highway, the ego in the middle lane, six scripted NPCs."""

from __future__ import annotations

import functools

import numpy as np
from highway_env.road.road import Road, RoadNetwork

from evoeye.scene import RoadMap
from evoeye.sim.npc import BrakeEvent, EgoVehicle, LaneChange, ScriptedVehicle
from evoeye.sim.roadmap import road_map_from_network
from evoeye.sim.world import Actor, World

N_LANES = 3
ROAD_LENGTH_M = 1400.0
EGO_LANE = 1  # lanes: 0 left (fast), 1 middle, 2 right
EGO_START_X_M = 200.0
MIN_SPACING_M = 9.0  # centre spacing enforced between NPCs spawned in one lane
OVERTAKER_CUT_BACK_M = 12.0  # the overtaker returns to the ego lane this far ahead of the ego
OVERTAKER_LANE_CHANGE_S = 2.0
CUT_IN_EARLIEST_S = 1.0  # no cut-in before the ADS has had a second to track the scene


def _place(wanted: list[tuple[int, float]]) -> list[float]:
    """Resolve spawn overlaps: in each lane, a later NPC too close to an earlier one moves back."""
    placed: list[tuple[int, float]] = [(EGO_LANE, EGO_START_X_M)]
    out = []
    for lane, x in wanted:
        for _ in range(len(placed) + 1):
            clash = [px for pl, px in placed if pl == lane and abs(px - x) < MIN_SPACING_M]
            if not clash:
                break
            x = min(clash) - MIN_SPACING_M
        placed.append((lane, x))
        out.append(x)
    return out


def _cut_in(p: dict[str, float], side: str, length_m: float) -> LaneChange:
    """A cut-in: once the NPC's rear is 0…trigger gap ahead of the ego's front (after 1 s)."""
    return LaneChange(
        EGO_LANE, p[f"{side}_cutin_duration_s"], start_s=CUT_IN_EARLIEST_S,
        ahead_min_m=length_m, ahead_max_m=length_m + p[f"{side}_cutin_trigger_gap_m"],
    )


@functools.cache
def _network() -> tuple[RoadNetwork, RoadMap]:
    """The static road and its map, built once per process (vehicles never modify them)."""
    net = RoadNetwork.straight_road_network(lanes=N_LANES, length=ROAD_LENGTH_M, speed_limit=40)
    return net, road_map_from_network("highway-cut-in", net, [("0", "1", EGO_LANE)])


def build_highway(p: dict[str, float], rng: np.random.Generator) -> tuple[World, float]:
    """The world for one concrete scenario, and the ego's cruise speed."""
    net, road_map = _network()
    road = Road(network=net, np_random=rng, record_history=False)
    lane = lambda i: net.get_lane(("0", "1", i))  # noqa: E731

    ego = EgoVehicle(road, lane(EGO_LANE).position(EGO_START_X_M, 0.0), 0.0, p["ego_speed_mps"])
    specs = [  # (lane, centre x, speed, brake, lane change)
        (EGO_LANE, EGO_START_X_M + p["lead_gap_m"] + ego.LENGTH, p["lead_speed_mps"],
         BrakeEvent(p["lead_brake_time_s"], p["lead_brake_decel_mps2"],
                    p["lead_brake_duration_s"]), None),
        (0, EGO_START_X_M + p["left_cutin_gap_m"], p["left_cutin_speed_mps"], None,
         _cut_in(p, "left", ego.LENGTH)),
        (2, EGO_START_X_M + p["right_cutin_gap_m"], p["right_cutin_speed_mps"], None,
         _cut_in(p, "right", ego.LENGTH)),
        (0, EGO_START_X_M + p["left_follow_gap_m"], p["left_follow_speed_mps"], None, None),
        (2, EGO_START_X_M + p["right_follow_gap_m"], p["right_follow_speed_mps"], None, None),
        (0, EGO_START_X_M + p["overtaker_gap_m"], p["overtaker_speed_mps"], None,
         LaneChange(EGO_LANE, OVERTAKER_LANE_CHANGE_S, ahead_min_m=OVERTAKER_CUT_BACK_M)),
    ]
    xs = _place([(s[0], s[1]) for s in specs])
    npcs = []
    placed = zip(specs, xs, strict=True)
    for actor_id, ((lane_i, _, speed, brake, change), x) in enumerate(placed, start=1):
        v = ScriptedVehicle(
            road, lane(lane_i).position(x, 0.0), 0.0, speed,
            target_speed=speed, target_lane_index=("0", "1", lane_i),
            brake=brake, lane_change=change, ego=ego,
        )
        npcs.append(Actor(actor_id, v))
    return World(road, ego, npcs, road_map), p["ego_speed_mps"]
