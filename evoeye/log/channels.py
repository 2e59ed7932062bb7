"""The MCAP channels of a run log: each topic bound to its schema file and to what produces it.

The schema files in `schemas/mcap/` are the single source of truth: a channel's MCAP schema name
is the file's `title` and the fields of its messages are the file's `properties`, read from the
file rather than retyped here (a contract test checks that they equal the dataclass fields).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from operator import attrgetter
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from evoeye.ads.messages import (
    ControlCommand,
    Localization,
    Obstacles,
    PlannedTrajectory,
    Predictions,
)
from evoeye.log import viz
from evoeye.scene import SceneState
from evoeye.sim.episode import Frame
from evoeye.sim.supervisor import SupervisorState

# The one place that locates the schemas (the project is installed editable).
SCHEMA_DIR = Path(__file__).resolve().parents[2] / "schemas" / "mcap"

MESSAGE_ENCODING = "json"
SCHEMA_ENCODING = "jsonschema"
RUN_RECORD = "evoeye.run"  # the MCAP metadata record holding the run's metadata
ROAD_MAP_ATTACHMENT = "evoeye.road_map"  # the MCAP attachment holding the RoadMap as JSON
RUN_SCHEMA_FILE = "run.v1.json"
ROAD_MAP_SCHEMA_FILE = "road_map.v1.json"


class Topics(NamedTuple):
    """The topic names of a run log; iterating gives them all."""

    localization: str = "/ads/localization"
    obstacles: str = "/ads/perception/obstacles"
    predictions: str = "/ads/prediction/trajectories"
    plan: str = "/ads/planning/trajectory"
    control: str = "/ads/control/command"
    ground_truth: str = "/sim/ground_truth"
    scene: str = "/viz/scene"
    map: str = "/viz/map"


TOPICS = Topics()
AGES_TOPIC = "/ads/message_ages"  # only in a log imported from another stack (evoeye.sources)


@cache
def load_schema(file_name: str) -> dict[str, Any]:
    """The parsed JSON Schema `schemas/mcap/<file_name>` (loaded once)."""
    return json.loads((SCHEMA_DIR / file_name).read_text(encoding="utf-8"))


def schema_fields(file_name: str) -> tuple[str, ...]:
    """The top-level property names of a schema, in file order."""
    return tuple(load_schema(file_name)["properties"])


def log_time_ns(t_s: float) -> int:
    """Log and publish time of a message: simulation time in integer nanoseconds."""
    return round(t_s * 1e9)


Encoder = Callable[[Any, int], dict[str, Any]]  # (source, log time ns) -> message dict


@dataclass(frozen=True)
class Channel:
    """A topic, its schema file, the type whose fields its messages carry and its encoder.

    `encode` takes a Frame for the per-frame channels and the RoadMap for /viz/map.
    """

    topic: str
    schema_file: str
    encode: Encoder
    message_type: type | None  # the dataclass mirrored field for field by the schema, if any
    # The message object itself, when orjson writes it as exactly `encode`'s dict (a dataclass
    # whose fields are the schema's, in order): the writer skips building the dict.
    message: Callable[[Any], Any] | None = None

    @property
    def schema(self) -> dict[str, Any]:
        return load_schema(self.schema_file)

    @property
    def schema_name(self) -> str:
        return self.schema["title"]

    @property
    def fields(self) -> tuple[str, ...]:
        return schema_fields(self.schema_file)


def _fields_encoder(schema_file: str, source: str) -> Encoder:
    """An encoder copying the schema's fields off the frame attribute at dotted path `source`."""
    fields = schema_fields(schema_file)
    get = attrgetter(*(f"{source}.{name}" for name in fields))

    def encode(frame: Frame, t_ns: int) -> dict[str, Any]:
        return dict(zip(fields, get(frame), strict=True))

    return encode


def _fields_channel(topic: str, schema_file: str, message_type: type, source: str) -> Channel:
    same_fields = getattr(message_type, "field_names", tuple)() == schema_fields(schema_file)
    return Channel(topic, schema_file, _fields_encoder(schema_file, source), message_type,
                   attrgetter(source) if same_fields else None)


SCENE_ARRAYS = ("x_m", "y_m", "heading_rad", "speed_mps", "accel_mps2", "length_m", "width_m")


def ground_truth_scene(message: dict[str, Any]) -> SceneState:
    """A ground-truth message back as the SceneState it was written from, without the
    occluders (the channel does not carry them)."""
    return SceneState(float(message["t_s"]), np.asarray(message["actor_id"], np.int64),
                      *(np.asarray(message[f], np.float64) for f in SCENE_ARRAYS),
                      np.asarray(message["crashed"], bool), bool(message["ego_collision"]),
                      int(message["collision_actor"]))


def _scene_update(frame: Frame, t_ns: int) -> dict[str, Any]:
    return viz.scene_update(frame.scene, frame.messages, t_ns)


# fmt: off
FRAME_CHANNELS: tuple[Channel, ...] = (
    _fields_channel(TOPICS.localization, "localization.v1.json", Localization,
                    "messages.localization"),
    _fields_channel(TOPICS.obstacles, "obstacles.v1.json", Obstacles, "messages.obstacles"),
    _fields_channel(TOPICS.predictions, "predictions.v1.json", Predictions, "messages.predictions"),
    _fields_channel(TOPICS.plan, "planned_trajectory.v1.json", PlannedTrajectory, "messages.plan"),
    _fields_channel(TOPICS.control, "control_command.v1.json", ControlCommand, "messages.control"),
    # SceneState carries every ground-truth field (vx_mps and vy_mps are properties of it).
    _fields_channel(TOPICS.ground_truth, "ground_truth.v1.json", SceneState, "scene"),
    Channel(TOPICS.scene, "scene_update.v1.json", _scene_update, None),
)
# fmt: on
MAP_CHANNEL = Channel(TOPICS.map, "scene_update.v1.json", viz.map_update, None)


def _not_simulated(frame: Frame, t_ns: int) -> dict[str, Any]:
    raise TypeError(f"{AGES_TOPIC} has no message in a simulated episode")


# The held messages' ages of a recording imported from another stack (evoeye.sources): written
# by `write_run`, never by `write_episode` (evoeye's ADS publishes every message at the frame).
AGES_CHANNEL = Channel(AGES_TOPIC, "message_ages.v1.json", _not_simulated, None)
CHANNELS: dict[str, Channel] = {c.topic: c for c in (*FRAME_CHANNELS, MAP_CHANNEL, AGES_CHANNEL)}
# Channels whose messages a log may lack altogether: their warehouse columns are then NULL.
OPTIONAL_TOPICS = frozenset({AGES_TOPIC})


# -- a supervised run's own channels (`evoeye supervise`), written beside the frame channels ------
SUPERVISOR_RECORD = "evoeye.supervisor"  # the MCAP metadata record of the trigger and fallback
SUPERVISOR_SCHEMA_FILE = "supervisor.v1.json"


def _supervisor_state(source: tuple[Frame, SupervisorState], t_ns: int) -> dict[str, Any]:
    state = source[1]
    return {name: getattr(state, name) for name in schema_fields(SUPERVISOR_SCHEMA_FILE)}


def _supervisor_label(source: tuple[Frame, SupervisorState], t_ns: int) -> dict[str, Any]:
    frame, state = source
    ego = frame.messages.localization
    acting = state.mode != "nominal"
    what = f"FALLBACK {state.mode} {state.accel_cmd_mps2:+.1f} m/s² · " if acting else ""
    return viz.ego_label(t_ns, ego.x_m, ego.y_m, ego.heading_rad,
                         f"{what}{state.trigger} {state.score:.2f}", acting,
                         ("supervisor/text", "supervisor/fallback"))


SUPERVISOR_CHANNELS: tuple[Channel, ...] = (
    Channel("/supervisor", SUPERVISOR_SCHEMA_FILE, _supervisor_state, SupervisorState),
    Channel("/viz/supervisor", "scene_update.v1.json", _supervisor_label, None),
)
