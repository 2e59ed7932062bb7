"""Contract: the schemas in schemas/mcap are valid, match the dataclasses, and every logged
message, the run record and the road-map attachment validate against them."""

from __future__ import annotations

import dataclasses
import io
import json
import re
from pathlib import Path

import orjson
import pytest
from jsonschema import Draft202012Validator
from mcap.reader import make_reader

from evoeye.ads.messages import Message
from evoeye.log import CHANNELS, TOPICS, read_run, write_episode
from evoeye.log.channels import (
    ROAD_MAP_ATTACHMENT,
    ROAD_MAP_SCHEMA_FILE,
    RUN_SCHEMA_FILE,
    SCHEMA_DIR,
    load_schema,
)
from evoeye.log.synthetic import synthetic_episode
from evoeye.scene import SceneState

SCHEMA_FILES = sorted(SCHEMA_DIR.glob("*.json"))
FOXGLOVE = "scene_update.v1.json"


@pytest.fixture(scope="module", params=[6, 0], ids=["6-obstacles", "no-obstacles"])
def log_path(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    episode = synthetic_episode(n_frames=30, seed=11, n_obstacles=request.param)
    return write_episode(episode, tmp_path_factory.mktemp("schemas") / "run.mcap")


def test_schema_files_exist_and_are_all_used() -> None:
    from evoeye.log.channels import SUPERVISOR_CHANNELS  # a supervised run's added channels
    from evoeye.monitor.replay import RISK_SCHEMA_FILE  # the replay's added channel

    used = {c.schema_file for c in (*CHANNELS.values(), *SUPERVISOR_CHANNELS)} | {
        RUN_SCHEMA_FILE, ROAD_MAP_SCHEMA_FILE, RISK_SCHEMA_FILE}
    assert {p.name for p in SCHEMA_FILES} == used


@pytest.mark.parametrize("path", SCHEMA_FILES, ids=lambda p: p.name)
def test_schema_file_is_valid_json_schema_2020_12(path: Path) -> None:
    assert re.fullmatch(r"[a-z_]+\.v\d+\.json", path.name)
    schema = json.loads(path.read_text())
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    Draft202012Validator.check_schema(schema)
    stem = path.name.removesuffix(".json")
    assert schema["$id"].endswith(stem) and schema["title"]


@pytest.mark.parametrize("topic", [t for t in TOPICS if CHANNELS[t].schema_file != FOXGLOVE])
def test_evoeye_schema_is_closed_and_all_required(topic: str) -> None:
    schema = CHANNELS[topic].schema
    assert schema["title"].startswith("evoeye.")
    assert schema["required"] == list(schema["properties"])
    assert schema["additionalProperties"] is False


@pytest.mark.parametrize(
    "topic",
    [
        t
        for t in TOPICS
        if isinstance(CHANNELS[t].message_type, type)
        and issubclass(CHANNELS[t].message_type, Message)
    ],
)
def test_message_dataclass_fields_equal_schema_properties(topic: str) -> None:
    channel = CHANNELS[topic]
    assert channel.message_type.field_names() == channel.fields


# static geometry the world hands perception with every scene, not per-frame ground truth: the
# same for every frame of a run, and rebuilt from the scenario when a run is re-simulated
STATIC_SCENE_FIELDS = {"occluders"}


def test_ground_truth_fields_are_scene_state_attributes() -> None:
    channel = CHANNELS[TOPICS.ground_truth]
    assert channel.message_type is SceneState
    stored = {f.name for f in dataclasses.fields(SceneState)} - STATIC_SCENE_FIELDS
    assert set(channel.fields) == stored | {"vx_mps", "vy_mps"}  # the two derived properties


def test_every_message_validates_against_its_schema(log_path: Path) -> None:
    run = read_run(log_path)
    validators = {t: Draft202012Validator(CHANNELS[t].schema) for t in TOPICS}
    for topic in TOPICS:
        messages = run.messages(topic)
        assert messages, topic
        for _, message in messages:
            validators[topic].validate(message)


def test_run_record_and_road_map_validate(log_path: Path) -> None:
    run = read_run(log_path)
    Draft202012Validator(load_schema(RUN_SCHEMA_FILE)).validate(run.metadata)
    with open(log_path, "rb") as f:
        (attachment,) = list(make_reader(f).iter_attachments())
    assert attachment.name == ROAD_MAP_ATTACHMENT
    Draft202012Validator(load_schema(ROAD_MAP_SCHEMA_FILE)).validate(orjson.loads(attachment.data))


def test_log_embeds_the_repository_schemas(log_path: Path) -> None:
    reader = make_reader(io.BytesIO(log_path.read_bytes()))
    summary = reader.get_summary()
    assert summary is not None
    topics = {c.topic: c for c in summary.channels.values()}
    assert set(topics) == set(TOPICS)
    for topic, channel in topics.items():
        schema = summary.schemas[channel.schema_id]
        assert channel.message_encoding == "json" and schema.encoding == "jsonschema"
        assert schema.name == CHANNELS[topic].schema_name
        assert orjson.loads(schema.data) == CHANNELS[topic].schema


# -- foxglove.SceneUpdate ------------------------------------------------------------------------
VIEWER_TYPES = {"boolean", "string", "number", "integer", "object", "array"}


def _entity() -> dict:
    return load_schema(FOXGLOVE)["properties"]["entities"]["items"]


def test_foxglove_schema_name_and_required_fields() -> None:
    schema = load_schema(FOXGLOVE)
    assert schema["title"] == "foxglove.SceneUpdate"  # the name Foxglove and Lichtblick draw
    assert set(schema["required"]) == {"deletions", "entities"}
    entity = _entity()
    assert set(entity["required"]) == {
        "timestamp",
        "frame_id",
        "id",
        "lifetime",
        "frame_locked",
        "metadata",
        "arrows",
        "cubes",
        "spheres",
        "cylinders",
        "lines",
        "triangles",
        "texts",
        "models",
    }
    assert set(entity["properties"]["timestamp"]["required"]) == {"sec", "nsec"}
    cube = entity["properties"]["cubes"]["items"]
    assert set(cube["required"]) == {"pose", "size", "color"}
    line = entity["properties"]["lines"]["items"]
    assert set(line["required"]) == {
        "type",
        "pose",
        "thickness",
        "scale_invariant",
        "points",
        "color",
        "colors",
        "indices",
    }
    assert set(line["properties"]["points"]["items"]["required"]) == {"x", "y", "z"}
    deletion = schema["properties"]["deletions"]["items"]
    assert set(deletion["required"]) == {"timestamp", "type", "id"}


def _walk(schema: dict, where: str):
    """Yield (path, field schema) for every object property, recursively."""
    for name, field in schema.get("properties", {}).items():
        yield f"{where}.{name}", field
        if field.get("type") == "object":
            yield from _walk(field, f"{where}.{name}")
        elif field.get("type") == "array" and field["items"].get("type") == "object":
            yield from _walk(field["items"], f"{where}.{name}[]")


def test_foxglove_schema_is_parsable_by_the_viewers() -> None:
    """Foxglove/Lichtblick read a JSON schema only if every field has one plain type and
    arrays hold scalars or objects (no $ref, no nested arrays, no type lists)."""
    for where, field in _walk(load_schema(FOXGLOVE), "SceneUpdate"):
        assert field.get("type") in VIEWER_TYPES, where
        if field["type"] == "array":
            assert field["items"].get("type") in VIEWER_TYPES - {"array"}, where


def test_enumerated_message_values_equal_the_schema_enums() -> None:
    from evoeye.ads.messages import PLANNING_DECISIONS, PREDICTION_MODES

    def enum(schema_file: str, field: str) -> list[str]:
        prop = json.loads((SCHEMA_DIR / schema_file).read_text())["properties"][field]
        return prop.get("enum") or prop["items"]["enum"]

    assert enum("predictions.v1.json", "model") == list(PREDICTION_MODES)
    assert enum("planned_trajectory.v1.json", "decision") == list(PLANNING_DECISIONS)
