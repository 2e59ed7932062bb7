"""`unprotected-intersection` (S2): a four-way intersection without signals, five NPCs.

The road is highway-env's own intersection (IntersectionEnv's network), with the ego's exit
extended so a 20 s run never runs off the map. Approaches: 0 south, 1 west, 2 north, 3 east; a
lane index (o<k>, ir<k>) is the approach from k, (ir<k>, il<j>) the move from k to j.
The NPCs do not yield (plain Road, not highway-env's RegulatedRoad): the ego must.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork

from evoeye.scene import RoadMap
from evoeye.sim.npc import EgoVehicle, ScriptedVehicle
from evoeye.sim.roadmap import road_map_from_network
from evoeye.sim.world import Actor, World

EGO_ROUTE = [("o0", "ir0", 0), ("ir0", "il2", 0), ("il2", "o2", 0), ("o2", "x2", 0)]
EGO_START_S_M = 50.0  # on the 100 m south approach: 50 m before the intersection
EGO_CRUISE_MPS = 10.0  # the intersection lanes' speed limit
NPC_ENTRY_S_M = 65.0  # NPCs appear 35 m before the intersection on their approach
EXIT_EXTENSION_M = 200.0

# name → (approach, destination); parameters are f"{name}_speed_mps", f"{name}_start_s"
NPC_MOVES = {
    "opp_left": (2, 3),  # north → east: left turn across the ego's path
    "cross_west": (1, 3),  # west → east, straight across
    "cross_east": (3, 1),  # east → west, straight across
    "right_merge": (3, 2),  # east → north: right turn into the ego's exit lane
    "left_merge": (1, 2),  # west → north: left turn into the ego's exit lane
}


@functools.cache
def _network() -> tuple[RoadNetwork, RoadMap]:
    """highway-env's intersection network (built once per process) plus the exit extension."""
    from highway_env.envs.intersection_env import IntersectionEnv

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = IntersectionEnv()
    env._make_road()
    net = env.road.network
    env.close()
    end = net.get_lane(("il2", "o2", 0)).position(net.get_lane(("il2", "o2", 0)).length, 0.0)
    net.add_lane(
        "o2", "x2",
        StraightLane(end, end + np.array([0.0, -EXIT_EXTENSION_M]),
                     line_types=[LineType.NONE, LineType.CONTINUOUS], speed_limit=10.0),
    )
    return net, road_map_from_network("unprotected-intersection", net, EGO_ROUTE)


def build_intersection(p: dict[str, float], rng: np.random.Generator) -> tuple[World, float]:
    """The world for one concrete scenario, and the ego's cruise speed."""
    net, road_map = _network()
    road = Road(network=net, np_random=rng, record_history=False,
                neighbour_vehicles_connected_lanes=True)
    start = net.get_lane(EGO_ROUTE[0])
    ego = EgoVehicle(road, start.position(EGO_START_S_M, 0.0),
                     start.heading_at(EGO_START_S_M), EGO_CRUISE_MPS)
    npcs = []
    for actor_id, (name, (src, dst)) in enumerate(NPC_MOVES.items(), start=1):
        speed = p[f"{name}_speed_mps"]
        route = [(f"o{src}", f"ir{src}", 0), (f"ir{src}", f"il{dst}", 0),
                 (f"il{dst}", f"o{dst}", 0)]
        lane = net.get_lane(route[0])
        v = ScriptedVehicle(
            road, lane.position(NPC_ENTRY_S_M, 0.0), lane.heading_at(NPC_ENTRY_S_M), speed,
            target_speed=speed, target_lane_index=route[0], route=route, ego=ego,
        )
        npcs.append(Actor(actor_id, v, spawn_s=p[f"{name}_start_s"]))
    return World(road, ego, npcs, road_map), EGO_CRUISE_MPS
