"""Foxglove `SceneUpdate` messages: what a viewer (Foxglove, Lichtblick) draws for a run.

Per frame, `/viz/scene` replaces the whole scene: one entity per actor (a cube; ego, NPC and
crashed actors in different colours), one with a line strip per predicted obstacle trajectory and
one with the planned ego trajectory. The road is drawn once, on its own topic `/viz/map`: a viewer
that seeks restores the latest message of each topic, so a map sent once on the per-frame topic
would vanish after the first seek. Dicts are built lean (shared constant parts, one list
comprehension per primitive kind) because this is the most expensive message of a frame.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from evoeye.ads.messages import FrameMessages
from evoeye.scene import EGO_ID, Lane, RoadMap, SceneState

FRAME_ID = "map"
ACTOR_HEIGHT_M = 1.5
LINE_Z_M = 0.2  # lines float a little above the road so cubes do not hide them

LINE_STRIP = 0  # foxglove.LineType
DELETE_ALL = 1  # foxglove.SceneEntityDeletionType

EGO_COLOR = {"r": 0.2, "g": 0.5, "b": 1.0, "a": 1.0}
NPC_COLOR = {"r": 0.75, "g": 0.75, "b": 0.75, "a": 1.0}
CRASHED_COLOR = {"r": 1.0, "g": 0.1, "b": 0.1, "a": 1.0}
PREDICTION_COLOR = {"r": 1.0, "g": 0.6, "b": 0.0, "a": 0.9}
PLAN_COLOR = {"r": 0.1, "g": 0.9, "b": 0.3, "a": 1.0}
LANE_COLOR = {"r": 0.55, "g": 0.55, "b": 0.55, "a": 1.0}
ROUTE_COLOR = {"r": 0.3, "g": 0.8, "b": 1.0, "a": 0.5}

_NONE: tuple = ()  # an empty primitive list, shared (orjson writes a tuple as an array)
_ZERO = {"sec": 0, "nsec": 0}
_IDENTITY = {
    "position": {"x": 0.0, "y": 0.0, "z": 0.0},
    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
}
# Every field a foxglove.SceneEntity requires, with the empty defaults; entities override a few.
_ENTITY: dict[str, Any] = {
    "timestamp": _ZERO,
    "frame_id": FRAME_ID,
    "id": "",
    "lifetime": _ZERO,
    "frame_locked": False,
    "metadata": _NONE,
    "arrows": _NONE,
    "cubes": _NONE,
    "spheres": _NONE,
    "cylinders": _NONE,
    "lines": _NONE,
    "triangles": _NONE,
    "texts": _NONE,
    "models": _NONE,
}


def stamp(t_ns: int) -> dict[str, int]:
    """A foxglove time {sec, nsec} from nanoseconds."""
    sec, nsec = divmod(t_ns, 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def line_strip(
    x_m: list[float], y_m: list[float], color: dict, thickness_m: float
) -> dict[str, Any]:
    """A foxglove.LinePrimitive joining the points (x_m[i], y_m[i]) in order."""
    return {
        "type": LINE_STRIP,
        "pose": _IDENTITY,
        "thickness": thickness_m,
        "scale_invariant": False,
        "points": [{"x": x, "y": y, "z": LINE_Z_M} for x, y in zip(x_m, y_m, strict=True)],
        "color": color,
        "colors": _NONE,
        "indices": _NONE,
    }


def actor_entities(scene: SceneState, ts: dict[str, int]) -> list[dict[str, Any]]:
    """One entity per actor, each a single cube at the actor's pose."""
    half = scene.heading_rad * 0.5
    rows = zip(
        scene.actor_id.tolist(),
        scene.x_m.tolist(),
        scene.y_m.tolist(),
        np.sin(half).tolist(),  # quaternion about +z: (0, 0, sin(h/2), cos(h/2))
        np.cos(half).tolist(),
        scene.length_m.tolist(),
        scene.width_m.tolist(),
        scene.crashed.tolist(),
        strict=True,
    )
    z = ACTOR_HEIGHT_M / 2
    return [
        {
            **_ENTITY,
            "timestamp": ts,
            "id": f"actor/{a}",
            "cubes": (
                {
                    "pose": {
                        "position": {"x": x, "y": y, "z": z},
                        "orientation": {"x": 0.0, "y": 0.0, "z": qz, "w": qw},
                    },
                    "size": {"x": length, "y": width, "z": ACTOR_HEIGHT_M},
                    "color": CRASHED_COLOR if crashed else EGO_COLOR if a == EGO_ID else NPC_COLOR,
                },
            ),
        }
        for a, x, y, qz, qw, length, width, crashed in rows
    ]


def trajectory_entities(messages: FrameMessages, ts: dict[str, int]) -> list[dict[str, Any]]:
    """The predicted obstacle trajectories and the planned ego trajectory, as line strips."""
    pred, plan = messages.predictions, messages.plan
    predicted = [
        line_strip(xs, ys, PREDICTION_COLOR, 0.15)
        for xs, ys in zip(np.asarray(pred.x_m).tolist(), np.asarray(pred.y_m).tolist(), strict=True)
    ]
    planned = line_strip(np.asarray(plan.x_m).tolist(), np.asarray(plan.y_m).tolist(), PLAN_COLOR, 0.3)
    return [
        {**_ENTITY, "timestamp": ts, "id": "predictions", "lines": predicted},
        {**_ENTITY, "timestamp": ts, "id": "plan", "lines": (planned,)},
    ]


def scene_update(scene: SceneState, messages: FrameMessages, t_ns: int) -> dict[str, Any]:
    """The /viz/scene message of one frame: delete the previous frame's entities, add this one's."""
    ts = stamp(t_ns)
    return {
        "deletions": ({"timestamp": ts, "type": DELETE_ALL, "id": ""},),
        "entities": actor_entities(scene, ts) + trajectory_entities(messages, ts),
    }


def _lane_strip(lane: Lane, color: dict, thickness_m: float) -> dict[str, Any]:
    points = np.asarray(lane.points, dtype=float)
    return line_strip(points[:, 0].tolist(), points[:, 1].tolist(), color, thickness_m)


def map_update(road_map: RoadMap, t_ns: int) -> dict[str, Any]:
    """The /viz/map message: lane centre lines and the ego route, kept forever (lifetime 0)."""
    lines = [_lane_strip(lane, LANE_COLOR, 0.1) for lane in road_map.lanes]
    lines.append(_lane_strip(road_map.route, ROUTE_COLOR, 0.6))
    entity = {**_ENTITY, "timestamp": stamp(t_ns), "id": "map", "frame_locked": True, "lines": lines}
    return {"deletions": _NONE, "entities": [entity]}
