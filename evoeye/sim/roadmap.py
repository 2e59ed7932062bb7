"""Turn a highway-env road network into the ADS's static `RoadMap` (dense centre polylines)."""

from __future__ import annotations

import numpy as np
from highway_env.road.lane import StraightLane
from highway_env.road.road import RoadNetwork

from evoeye.scene import Lane, RoadMap

SAMPLE_STEP_M = 1.0  # polyline spacing


def _sample(lane, step_m: float = SAMPLE_STEP_M) -> np.ndarray:
    n = max(2, int(np.ceil(lane.length / step_m)) + 1)
    s = np.linspace(0.0, lane.length, n)
    if isinstance(lane, StraightLane):
        return lane.start + s[:, None] * lane.direction  # (K, 2)
    return np.array([lane.position(si, 0.0) for si in s])  # (K, 2)


def road_map_from_network(
    name: str, network: RoadNetwork, route: list[tuple[str, str, int]],
    yielding: frozenset[tuple[str, str]] = frozenset(),
) -> RoadMap:
    """Every lane of `network`, plus the ego route as one polyline through the `route` lanes.
    Lanes (from, to) in `yielding` give way to the route's traffic where they end."""
    lanes = []
    for _from, tos in network.graph.items():
        for _to, group in tos.items():
            for i, lane in enumerate(group):
                lanes.append(
                    Lane(
                        lane_id=f"{_from}:{_to}:{i}",
                        points=_sample(lane),
                        width_m=float(lane.width_at(0.0)),
                        speed_limit_mps=float(lane.speed_limit or 30.0),
                        yields_to_route=(_from, _to) in yielding,
                    )
                )
    parts = [_sample(network.get_lane(idx)) for idx in route]
    pts = [parts[0]] + [p[1:] for p in parts[1:]]  # drop joints shared by consecutive lanes
    first = network.get_lane(route[0])
    route_lane = Lane(
        lane_id="route",
        points=np.concatenate(pts),
        width_m=float(first.width_at(0.0)),
        speed_limit_mps=float(first.speed_limit or 30.0),
    )
    return RoadMap(name=name, lanes=tuple(lanes), route=route_lane)
