"""The two per-run records beside the channels: the `evoeye.run` metadata and the road map.

MCAP metadata is string → string. A field whose schema type is "string" is stored as is; every
other field as its JSON text ("null" for an absent number), so `decode_run` types values back
from `schemas/mcap/run.v1.json` alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import orjson

from evoeye.log.channels import RUN_SCHEMA_FILE, load_schema, schema_fields
from evoeye.scenarios import SCENARIOS
from evoeye.scene import Lane, RoadMap
from evoeye.sim.episode import Episode

SIMULATOR_LABELS = "simulator"  # label_source of a run evoeye simulated: its own ground truth
UNLABELLED = "none"  # label_source of a recording without ground truth (schemas/mcap/run.v1.json)


def _is_string(prop: dict[str, Any]) -> bool:
    return prop.get("type") == "string"


def _float_or_none(value: float | None) -> float | None:
    return None if value is None else float(value)


def param_names(scenario: str, n_params: int) -> list[str]:
    """The parameter names of a logical scenario; positional names p0… if it is not known."""
    known = SCENARIOS.get(scenario)
    if known is not None and known.dim == n_params:
        return list(known.names)
    return [f"p{i}" for i in range(n_params)]


def run_values(episode: Episode) -> dict[str, Any]:
    """The typed run metadata of an episode (the values `decode_run` gives back)."""
    spec, out = episode.spec, episode.outcome
    values = {
        "scenario_id": spec.scenario_id,
        "logical_scenario": spec.scenario,
        "param_names": param_names(spec.scenario, len(spec.params)),
        "params": [float(v) for v in spec.params],
        "seed": int(spec.seed),
        "batch": spec.batch,
        "source": spec.source,
        "round": int(spec.round),
        "ads_profile": spec.ads,
        "world": spec.world,
        "software_version": episode.software_version,
        "rate_hz": float(episode.rate_hz),
        "status": out.status,
        "reason": out.reason,
        "collided": bool(out.collided),
        "collision_time_s": _float_or_none(out.collision_time_s),
        "other_actor": None if out.other_actor is None else int(out.other_actor),
        "duration_s": float(out.duration_s),
        "min_distance_m": _float_or_none(out.min_distance_m),
        "label_source": SIMULATOR_LABELS,
    }
    return {name: values[name] for name in schema_fields(RUN_SCHEMA_FILE)}


def encode_run(values: dict[str, Any]) -> dict[str, str]:
    """Typed run metadata → the string → string MCAP metadata record. A field the schema marks
    `omitted_at_default` is left out at its default (absent, it decodes as that default)."""
    props = load_schema(RUN_SCHEMA_FILE)["properties"]
    return {
        name: values[name] if _is_string(prop) else orjson.dumps(values[name]).decode()
        for name, prop in props.items()
        if not (prop.get("omitted_at_default") and values.get(name, prop["default"])
                == prop["default"])
    }


def _typed(prop: dict[str, Any], value: Any, name: str) -> Any:
    """`value` checked against a schema property's type; numbers come back as float."""
    types = prop["type"] if isinstance(prop["type"], list) else [prop["type"]]
    if value is None and "null" in types:
        return None
    if "array" in types and isinstance(value, list):
        return [_typed(prop["items"], v, name) for v in value]
    if "boolean" in types and isinstance(value, bool):
        return value
    if isinstance(value, bool):  # a bool is an int in Python; it is never a number here
        raise ValueError(f"{name}: expected {types}, got {value!r}")
    if "integer" in types and isinstance(value, int):
        return value
    if "number" in types and isinstance(value, int | float):
        return float(value)
    if "string" in types and isinstance(value, str):
        return value
    raise ValueError(f"{name}: expected {types}, got {value!r}")


def decode_run(record: dict[str, str]) -> dict[str, Any]:
    """The MCAP metadata record → typed run metadata; ValueError naming the field if malformed.
    A field the schema does not require takes its schema default when the record lacks it."""
    schema = load_schema(RUN_SCHEMA_FILE)
    props = schema["properties"]
    missing = [name for name in schema["required"] if name not in record]
    if missing:
        raise ValueError(f"missing fields {missing}")
    typed = {}
    for name, prop in props.items():
        if name not in record:
            typed[name] = prop["default"]
            continue
        raw = record[name]
        try:
            value = raw if _is_string(prop) else orjson.loads(raw)
        except orjson.JSONDecodeError:
            raise ValueError(f"{name}: not JSON: {raw!r}") from None
        typed[name] = _typed(prop, value, name)
    return typed


def _lane_dict(lane: Lane) -> dict[str, Any]:
    return {
        "lane_id": lane.lane_id,
        "points": np.ascontiguousarray(lane.points, dtype=np.float64),
        "width_m": float(lane.width_m),
        "speed_limit_mps": float(lane.speed_limit_mps),
        "yields_to_route": bool(lane.yields_to_route),
    }


def road_map_dict(road_map: RoadMap) -> dict[str, Any]:
    """The RoadMap as a dict in the layout of `schemas/mcap/road_map.v1.json` (arrays kept)."""
    return {
        "name": road_map.name,
        "lanes": [_lane_dict(lane) for lane in road_map.lanes],
        "route": _lane_dict(road_map.route),
    }


def _lane(d: dict[str, Any]) -> Lane:
    points = np.asarray(d["points"], dtype=np.float64).reshape(-1, 2)
    return Lane(d["lane_id"], points, float(d["width_m"]), float(d["speed_limit_mps"]),
                bool(d.get("yields_to_route", False)))


def decode_road_map(data: bytes) -> RoadMap:
    """The road-map attachment's JSON bytes → RoadMap."""
    d = orjson.loads(data)
    return RoadMap(d["name"], tuple(_lane(lane) for lane in d["lanes"]), _lane(d["route"]))
