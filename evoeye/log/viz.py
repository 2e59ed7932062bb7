"""Foxglove `SceneUpdate` messages: what a viewer (Foxglove, Lichtblick) draws for a run.

Per frame, `/viz/scene` replaces the whole scene: one entity per actor (a cube; ego, NPC and
crashed actors in different colours), one with a line strip per predicted obstacle trajectory and
one with the planned ego trajectory. The road is drawn once, on its own topic `/viz/map`: a viewer
that seeks restores the latest message of each topic, so a map sent once on the per-frame topic
would vanish after the first seek.

This is the most expensive message of a frame (a third of the logging budget), so it is built
lean: constant parts are serialised once (orjson Fragments), and a trajectory is drawn through at
most MAX_LINE_POINTS of its points, both ends kept (the full trajectories are on their own
channels; the drawing only has to look right).
"""

from __future__ import annotations

from functools import cache
from math import cos, sin
from typing import Any

import numpy as np
import orjson

from evoeye.ads.messages import FrameMessages
from evoeye.scene import EGO_ID, Lane, RoadMap, SceneState

FRAME_ID = "map"
ACTOR_HEIGHT_M = 1.5
LINE_Z_M = 0.2  # lines float a little above the road so cubes do not hide them
MAX_LINE_POINTS = 10  # trajectories are drawn through at most this many of their points

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


def _json(value: Any) -> orjson.Fragment:
    """A constant, serialised once: orjson copies a Fragment's bytes instead of re-encoding."""
    return orjson.Fragment(orjson.dumps(value))


_ZERO = _json({"sec": 0, "nsec": 0})
_IDENTITY = _json(
    {
        "position": {"x": 0.0, "y": 0.0, "z": 0.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    }
)
_EGO, _NPC, _CRASHED = _json(EGO_COLOR), _json(NPC_COLOR), _json(CRASHED_COLOR)
_PREDICTION, _PLAN = _json(PREDICTION_COLOR), _json(PLAN_COLOR)
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


def points(x_m: list[float], y_m: list[float], z_m: float = LINE_Z_M) -> list[dict[str, float]]:
    """foxglove.Point3 dicts of a polyline (x_m and y_m of equal length)."""
    return [{"x": x, "y": y, "z": z_m} for x, y in zip(x_m, y_m, strict=False)]  # hot: unchecked


def line_strip(
    pts: list[dict[str, float]], color: dict | orjson.Fragment, thickness_m: float
) -> dict[str, Any]:
    """A foxglove.LinePrimitive joining the points in order."""
    return {
        "type": LINE_STRIP,
        "pose": _IDENTITY,
        "thickness": thickness_m,
        "scale_invariant": False,
        "points": pts,
        "color": color,
        "colors": _NONE,
        "indices": _NONE,
    }


def actor_entities(scene: SceneState, ts: dict[str, int]) -> list[dict[str, Any]]:
    """One entity per actor, each a single cube at the actor's pose."""
    z = ACTOR_HEIGHT_M / 2
    rows = zip(
        scene.actor_id.tolist(),
        scene.x_m.tolist(),
        scene.y_m.tolist(),
        scene.heading_rad.tolist(),
        scene.length_m.tolist(),
        scene.width_m.tolist(),
        scene.crashed.tolist(),
        strict=True,
    )
    # A handful of actors: plain Python math is cheaper than numpy's per-call overhead here.
    return [
        {
            **_ENTITY,
            "timestamp": ts,
            "id": f"actor/{a}",
            "cubes": (
                {
                    "pose": {
                        "position": {"x": x, "y": y, "z": z},
                        # rotation by the heading about +z: (0, 0, sin(h/2), cos(h/2))
                        "orientation": {"x": 0.0, "y": 0.0, "z": sin(0.5 * h), "w": cos(0.5 * h)},
                    },
                    "size": {"x": length, "y": width, "z": ACTOR_HEIGHT_M},
                    "color": _CRASHED if crashed else _EGO if a == EGO_ID else _NPC,
                },
            ),
        }
        for a, x, y, h, length, width, crashed in rows
    ]


@cache
def drawn(k: int) -> np.ndarray:
    """Indices of the at most MAX_LINE_POINTS points drawn of a k-point line, both ends kept."""
    return np.unique(np.linspace(0, k - 1, min(k, MAX_LINE_POINTS)).round().astype(np.intp))


def trajectory_entities(messages: FrameMessages, ts: dict[str, int]) -> list[dict[str, Any]]:
    """The predicted obstacle trajectories and the planned ego trajectory, as line strips."""
    pred, plan = messages.predictions, messages.plan
    px, py = np.asarray(pred.x_m, dtype=float), np.asarray(pred.y_m, dtype=float)
    idx = drawn(px.shape[-1])  # take() is ~4x faster than fancy indexing on these small arrays
    predicted = [
        line_strip(points(xs, ys), _PREDICTION, 0.15)
        for xs, ys in zip(px.take(idx, -1).tolist(), py.take(idx, -1).tolist(), strict=True)
    ]
    qx, qy = np.asarray(plan.x_m, dtype=float), np.asarray(plan.y_m, dtype=float)
    idx = drawn(qx.shape[-1])
    planned = line_strip(points(qx.take(idx).tolist(), qy.take(idx).tolist()), _PLAN, 0.3)
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


def _corners(xy: np.ndarray, tol_rad: float = 1e-3) -> np.ndarray:
    """The polyline without its collinear interior points: a straight lane keeps its 2 ends."""
    if len(xy) <= 2:
        return xy
    d = np.diff(xy, axis=0)
    turn = np.abs(np.angle(np.exp(1j * np.diff(np.arctan2(d[:, 1], d[:, 0]))))) > tol_rad
    keep = np.concatenate(([0], np.flatnonzero(turn) + 1, [len(xy) - 1]))
    return xy[keep]


def _lane_strip(lane: Lane, color: dict, thickness_m: float) -> dict[str, Any]:
    xy = _corners(np.asarray(lane.points, dtype=float))
    return line_strip(points(xy[:, 0].tolist(), xy[:, 1].tolist(), 0.0), color, thickness_m)


def map_update(road_map: RoadMap, t_ns: int) -> dict[str, Any]:
    """The /viz/map message: lane centre lines and the ego route, kept forever (lifetime 0)."""
    lines = [_lane_strip(lane, LANE_COLOR, 0.1) for lane in road_map.lanes]
    lines.append(_lane_strip(road_map.route, ROUTE_COLOR, 0.6))
    entity = {
        **_ENTITY,
        "timestamp": stamp(t_ns),
        "id": "map",
        "frame_locked": True,
        "lines": lines,
    }
    return {"deletions": _NONE, "entities": [entity]}


# -- labels over the ego (a monitor's risk, the supervisor's state) ----------------------------
TEXT_HEIGHT_M = 4.0
ALERT_BOX_M = (7.0, 3.5, 2.0)  # drawn around the ego's pose: length, width, height
CALM_TEXT_COLOR = {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0}
ALERT_BOX_COLOR = {**CRASHED_COLOR, "a": 0.35}


def _labelled(t_ns: int, entity_id: str, **primitives: Any) -> dict[str, Any]:
    return {**_ENTITY, "timestamp": stamp(t_ns), "id": entity_id, "metadata": [],
            **{kind: primitives.get(kind, []) for kind in
               ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts",
                "models")}}


def ego_label(t_ns: int, x_m: float, y_m: float, heading_rad: float, text: str, alert: bool,
              ids: tuple[str, str]) -> dict[str, Any]:
    """A SceneUpdate replacing the previous one of its topic: `text` above the ego at (x_m,
    y_m), red while `alert`, and while alert a translucent red box around the ego; `ids` are
    the entity ids of the text and of the box."""
    h = float(heading_rad)
    orientation = {"x": 0.0, "y": 0.0, "z": sin(0.5 * h), "w": cos(0.5 * h)}
    at = {"x": float(x_m), "y": float(y_m)}
    label = {
        "pose": {"position": {**at, "z": TEXT_HEIGHT_M}, "orientation": orientation},
        "billboard": True, "font_size": 18.0, "scale_invariant": True,
        "color": CRASHED_COLOR if alert else CALM_TEXT_COLOR, "text": text,
    }
    entities = [_labelled(t_ns, ids[0], texts=[label])]
    if alert:
        length, width, height = ALERT_BOX_M
        box = {"pose": {"position": {**at, "z": height / 2}, "orientation": orientation},
               "size": {"x": length, "y": width, "z": height}, "color": ALERT_BOX_COLOR}
        entities.append(_labelled(t_ns, ids[1], cubes=[box]))
    return {"deletions": [{"timestamp": stamp(t_ns), "type": DELETE_ALL, "id": ""}],
            "entities": entities}
