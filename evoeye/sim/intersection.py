"""`unprotected-intersection` (S2): a four-way intersection without signals, five NPCs.

The road is highway-env's own intersection (IntersectionEnv's network) with every approach and
exit lengthened by `EXTENSION_M`, so every actor exists from t = 0 far beyond the ego's sensors
and a 20 s run never runs off the map. Approaches: 0 south, 1 west, 2 north, 3 east; a lane
index (o<k>, ir<k>) is the approach from k, (ir<k>, il<j>) the move from k to j, (e<k>, o<k>)
and (o<k>, x<k>) the added entry and exit.

Timing is relative, not a clock: the ego starts a seeded 20–160 m before the box (so the
critical moment comes at a different time in every run), and each NPC is placed so that, at
its own speed profile, it reaches its first conflict with the ego's path `<name>_offset_s`
after the ego would at its cruise speed. The NPCs slow for the turns (curvature-limited speed)
and follow vehicles ahead in their lane, but do not yield: the ego must.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork

from evoeye.scene import RoadMap
from evoeye.sim.npc import DriverModel, EgoVehicle, Npc, curve_speed
from evoeye.sim.path import Path
from evoeye.sim.roadmap import road_map_from_network
from evoeye.sim.traffic import Conflict, YieldToEgo
from evoeye.sim.world import World

EXTENSION_M = 320.0
EGO_ROUTE = [("e0", "o0", 0), ("o0", "ir0", 0), ("ir0", "il2", 0), ("il2", "o2", 0),
             ("o2", "x2", 0)]
EGO_APPROACH_M = (20.0, 160.0)  # the ego starts this far (seeded, uniform) before the box
EGO_CRUISE_MPS = 10.0  # the intersection lanes' speed limit
CONFLICT_RADIUS_M = 2.5  # paths closer than this share a conflict point (timing parameters)
CROSSING_RADIUS_M = 4.5  # a waiting NPC's centre keeps this far from the other's path (its
# half-diagonal, 2.7 m, plus the other's half-width and a margin)
MIN_SPACING_M = 10.0  # centre spacing between NPCs placed on one approach

# a building fills each corner from its setback to BUILDING_TO_M off the centre lines, both
# ways: crossing traffic shows late, as at a city corner. The corners east of the ego's road
# stand closer than the western ones (a wider pavement there), so the two crossings show at
# different moments
BUILDING_SETBACK_M = {"east": 12.5, "west": 18.0}
BUILDING_TO_M = 90.0
EGO_CLEARANCE_M = 6.5  # a turning NPC yielding to the ego stops this far from its route
TURN_GAP_S = 2.0  # a turning NPC goes if the ego would reach the crossing this much after it
# name → (approach, destination); parameters are f"{name}_speed_mps", f"{name}_offset_s"
NPC_MOVES = {
    "opp_left": (2, 3),  # north → east: left turn across the ego's path
    "cross_west": (1, 3),  # west → east, straight across
    "cross_east": (3, 1),  # east → west, straight across
    "right_merge": (3, 2),  # east → north: right turn into the ego's exit lane
    "left_merge": (1, 2),  # west → north: left turn into the ego's exit lane
}
# turning traffic yields to the ego's straight movement (accepting short gaps); the crossing
# traffic does not
TURNS_YIELD = ("opp_left", "right_merge", "left_merge")
# the rule of the road the ADS's map encodes (priority to the right): traffic from the ego's
# left (west) gives way to it; the ego gives way to traffic from its right (east). The west
# crossing car does not keep to it — a right-of-way violation the ADS must see in time
GIVE_WAY_APPROACHES = (1,)


def _route(src: int, dst: int) -> list[tuple[str, str, int]]:
    return [(f"e{src}", f"o{src}", 0), (f"o{src}", f"ir{src}", 0), (f"ir{src}", f"il{dst}", 0),
            (f"il{dst}", f"o{dst}", 0), (f"o{dst}", f"x{dst}", 0)]


@functools.cache
def _network() -> tuple[RoadNetwork, RoadMap]:
    """highway-env's intersection network (built once per process) with long approaches."""
    from highway_env.envs.intersection_env import IntersectionEnv

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = IntersectionEnv()
    env._make_road()
    net = env.road.network
    env.close()
    for k in range(4):
        entry = net.get_lane((f"o{k}", f"ir{k}", 0))
        net.add_lane(f"e{k}", f"o{k}", StraightLane(
            entry.start - EXTENSION_M * entry.direction, entry.start,
            line_types=[LineType.NONE, LineType.CONTINUOUS], speed_limit=EGO_CRUISE_MPS))
        out = net.get_lane((f"il{k}", f"o{k}", 0))
        net.add_lane(f"o{k}", f"x{k}", StraightLane(
            out.end, out.end + EXTENSION_M * out.direction,
            line_types=[LineType.NONE, LineType.CONTINUOUS], speed_limit=EGO_CRUISE_MPS))
    # only the lane that ends at the box gives way; its 320 m extension ends 100 m before it
    yielding = frozenset((f"o{k}", f"ir{k}") for k in GIVE_WAY_APPROACHES)
    return net, road_map_from_network("unprotected-intersection", net, EGO_ROUTE, yielding)


@functools.cache
def _path(route: tuple[tuple[str, str, int], ...]) -> Path:
    net, _ = _network()
    return Path.from_lanes([net.get_lane(idx) for idx in route])


@functools.cache
def _conflict(src: int, dst: int) -> tuple[float, float]:
    """(s on the NPC's path, s on the ego's path) of the NPC's first conflict with the ego."""
    hit = _path(tuple(_route(src, dst))).first_conflict(_path(tuple(EGO_ROUTE)), CONFLICT_RADIUS_M)
    if hit is None:
        raise ValueError(f"the move {src}→{dst} never meets the ego's path")
    return hit


@functools.cache
def _npc_crossings() -> tuple[tuple[int, int, float, float, float, float, int | None], ...]:
    """(row i, row j, s_i, s_j, stop_i, stop_j, first) for every pair of NPC moves from different
    approaches whose paths meet (rows as in the world: NPCs from 1). `first` is the straight
    move where the other turns (turning traffic gives way to straight traffic), else None:
    whoever would arrive first goes."""
    moves = list(NPC_MOVES.values())
    out = []
    for a in range(len(moves)):
        for b in range(a + 1, len(moves)):
            if moves[a][0] == moves[b][0]:  # one approach: they follow each other
                continue
            pa, pb = _path(tuple(_route(*moves[a]))), _path(tuple(_route(*moves[b])))
            hit = pa.first_conflict(pb, CONFLICT_RADIUS_M)
            if hit is not None:
                stop_a = pa.stop_before(pb, hit[0], hit[1], CROSSING_RADIUS_M)
                stop_b = pb.stop_before(pa, hit[1], hit[0], CROSSING_RADIUS_M)
                straight = [r for r, (src, dst) in ((a + 1, moves[a]), (b + 1, moves[b]))
                            if (src - dst) % 2 == 0]
                out.append((a + 1, b + 1, *hit, stop_a, stop_b,
                            straight[0] if len(straight) == 1 else None))
    return tuple(out)


@functools.cache
def _ego_crossing(src: int, dst: int) -> tuple[float, float, float]:
    """(s on the NPC's path, s on the ego's route, the NPC's stop point) where it meets the ego."""
    s_npc, s_ego = _conflict(src, dst)
    stop = _path(tuple(_route(src, dst))).stop_before(
        _path(tuple(EGO_ROUTE)), s_npc, s_ego, EGO_CLEARANCE_M)
    return s_npc, s_ego, stop


def _box_entry_s() -> float:
    net, _ = _network()
    return sum(net.get_lane(idx).length for idx in EGO_ROUTE[:2])


def start_for_arrival(path: Path, speed_mps: float, s_conflict: float, t_arrive_s: float,
             driver: DriverModel) -> float:
    """Where to start on `path` to reach s_conflict after t_arrive_s at the path's speed profile
    (the desired speed, curve-limited)."""
    v = np.minimum(curve_speed(path, driver), speed_mps)
    k = path.index(s_conflict)
    dt = np.diff(path.s[: k + 1]) / np.maximum(0.5 * (v[:k] + v[1 : k + 1]), 0.1)
    t_to_go = np.concatenate((np.cumsum(dt[::-1])[::-1], [0.0]))  # (k+1,) time to the conflict
    j = int(np.searchsorted(-t_to_go, -t_arrive_s))  # first sample with t_to_go <= t_arrive
    return float(path.s[min(j, k)])


def build_intersection(p: dict[str, float], rng: np.random.Generator) -> tuple[World, float]:
    """The world for one concrete scenario, and the ego's cruise speed."""
    net, road_map = _network()
    road = Road(network=net, np_random=rng, record_history=False)
    ego_path = _path(tuple(EGO_ROUTE))
    s_ego = _box_entry_s() - float(rng.uniform(*EGO_APPROACH_M))
    x, y, h = ego_path.pose(s_ego)
    ego = EgoVehicle(road, [x, y], h, EGO_CRUISE_MPS)
    driver = DriverModel()
    placed: dict[int, list[float]] = {}
    npcs = []
    for name, (src, dst) in NPC_MOVES.items():
        speed = p[f"{name}_speed_mps"]
        path = _path(tuple(_route(src, dst)))
        s_npc, s_ego_conflict = _conflict(src, dst)
        t_ego = (s_ego_conflict - s_ego) / EGO_CRUISE_MPS
        s0 = start_for_arrival(path, speed, s_npc, t_ego + p[f"{name}_offset_s"], driver)
        for other in sorted(placed.get(src, []), reverse=True):  # same approach: keep spacing
            if abs(other - s0) < MIN_SPACING_M:
                s0 = other - MIN_SPACING_M
        s0 = max(s0, 0.0)
        placed.setdefault(src, []).append(s0)
        v0 = min(speed, float(curve_speed(path, driver)[path.index(s0)]))
        npcs.append(Npc(road, path, s0, v0, desired_speed_mps=speed, driver=driver))
    conflicts = [Conflict(*c) for c in _npc_crossings()]
    yields = [YieldToEgo(row, *_ego_crossing(*NPC_MOVES[name]), gap_s=TURN_GAP_S)
              for row, name in enumerate(NPC_MOVES, start=1) if name in TURNS_YIELD]
    return World(road, ego, npcs, road_map, conflicts, yields, ego_path,
                 occluders=_buildings()), EGO_CRUISE_MPS


@functools.cache
def _buildings() -> np.ndarray:
    """(4, 4) one building per corner, [x_min, y_min, x_max, y_max]."""
    b = BUILDING_TO_M
    corners = []
    for sx in (1, -1):
        a = BUILDING_SETBACK_M["east" if sx > 0 else "west"]
        corners += [[a if sx > 0 else -b, a if sy > 0 else -b, b if sx > 0 else -a,
                     b if sy > 0 else -a] for sy in (1, -1)]
    return np.array(corners, dtype=float)
