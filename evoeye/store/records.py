"""One run log → its warehouse rows: a `scenarios` row and a `frames` table (pure functions).

The frame columns are derived from the DDL, not listed here: column `<prefix><field>` takes
field `<field>` of the topic behind `<prefix>` (`loc_` ← /ads/localization, …, `gt_` ←
/sim/ground_truth); a `gt_` scalar column of a per-actor field takes the ego's entry (actor 0).
Message i of every topic belongs to frame i; the ground-truth channel is the frame clock. A log
without any message on an optional topic (`OPTIONAL_TOPICS`: the message ages of an imported
recording) gets NULL in that topic's columns.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from datetime import datetime
from functools import cache
from typing import Any, Protocol

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from evoeye.ads.messages import FrameMessages
from evoeye.ads.profiles import DEFAULT_PROFILE
from evoeye.log import TOPICS
from evoeye.log.channels import AGES_TOPIC, CHANNELS, OPTIONAL_TOPICS
from evoeye.log.records import SIMULATOR_LABELS
from evoeye.scene import EGO_ID
from evoeye.store.features import FEATURES, FeatureSpec, FrameFeatures, frame_features, pack
from evoeye.store.live_columns import live_column
from evoeye.store.schema import PARTITION_KEYS, file_schema, table_schema

PREFIX_TOPIC = {
    "loc_": TOPICS.localization,
    "obs_": TOPICS.obstacles,
    "pred_": TOPICS.predictions,
    "plan_": TOPICS.plan,
    "ctrl_": TOPICS.control,
    "age_": AGES_TOPIC,
    "gt_": TOPICS.ground_truth,
}
# Where a column name is not prefix + field name (the column says what the field means).
FIELD_OF_COLUMN = {"obs_class": "obj_class"}
# Columns the converter fills itself rather than from a message field.
OWN_COLUMNS = ("scenario_id", "frame", "t_s", "ingest_id")
FRAME_CLOCK = TOPICS.ground_truth
TIME_TOLERANCE_S = 1e-6
PARTITION_VALUE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


class RunRecordError(ValueError):
    """A log that reads but cannot be a warehouse record (missing topic, misaligned frames…)."""


class RunSource(Protocol):
    """What the converter needs of a run log: `evoeye.log.RunLog` (read from its file, message
    values as JSON decodes them) or `evoeye.log.episode_log.EpisodeLog` (from the Episode in
    memory, values as published: `decoded` False)."""

    metadata: dict[str, Any]
    decoded: bool

    def messages(self, topic: str) -> list[tuple[int, dict[str, Any]]]: ...


def _source(column: str) -> tuple[str, str]:
    """(topic, field) feeding a frames column."""
    for prefix, topic in PREFIX_TOPIC.items():
        if column.startswith(prefix):
            return topic, FIELD_OF_COLUMN.get(column, column[len(prefix) :])
    raise RunRecordError(f"frames column {column!r} has no module prefix")


def frame_column_sources() -> dict[str, tuple[str, str]]:
    """Every message-fed frames column → (topic, field), in DDL order."""
    return {f.name: _source(f.name) for f in file_schema("frames") if f.name not in OWN_COLUMNS}


def _aligned_messages(run: RunSource, topics: Sequence[str]) -> dict[str, list[dict[str, Any]]]:
    """The message dicts of each topic, checked to be one per frame of the frame clock."""
    clock = [msg for _, msg in run.messages(FRAME_CLOCK)]
    times = [float(m["t_s"]) for m in clock]
    out = {FRAME_CLOCK: clock}
    for topic in topics:
        if topic in out:
            continue
        msgs = [msg for _, msg in run.messages(topic)]
        if not msgs and topic in OPTIONAL_TOPICS:
            out[topic] = [None] * len(clock)
            continue
        if len(msgs) != len(clock):
            raise RunRecordError(
                f"{topic} has {len(msgs)} messages for {len(clock)} frames of {FRAME_CLOCK}"
            )
        for i, (m, t) in enumerate(zip(msgs, times, strict=True)):
            if abs(float(m["t_s"]) - t) > TIME_TOLERANCE_S:
                raise RunRecordError(f"{topic} message {i} at t={m['t_s']} s, frame at t={t} s")
        out[topic] = msgs
    return out


def _is_array_field(topic: str, field: str) -> bool:
    """The channel schema (schemas/mcap) declares `field` of `topic` as an array."""
    return CHANNELS[topic].schema["properties"][field]["type"] == "array"


def _column(msgs: list[dict[str, Any]], field: str, typ: pa.DataType, ego: bool,
            decoded: bool) -> pa.Array:
    # ego: a per-actor ground-truth array, whose first row is always the ego's
    if msgs and msgs[0] is None:  # an optional topic the log has no message on
        return pa.nulls(len(msgs), typ)
    values = [m[field][0] for m in msgs] if ego else [m[field] for m in msgs]
    return pa.array(values, type=typ) if decoded else live_column(values, typ)


def frames_table(run: RunSource, scenario_id: str, ingest_id: str) -> pa.Table:
    """The frames of one run as an Arrow table in the Parquet file schema (no partition keys);
    the same from a run's log and from its Episode in memory."""
    schema = file_schema("frames")
    sources = frame_column_sources()
    try:
        by_topic = _aligned_messages(run, sorted({t for t, _ in sources.values()}))
        clock = by_topic[FRAME_CLOCK]
        for i, m in enumerate(clock):
            if m["actor_id"] is None or len(m["actor_id"]) == 0 or m["actor_id"][0] != EGO_ID:
                raise RunRecordError(f"ground truth of frame {i} does not start with the ego")
        n = len(clock)
        columns: dict[str, pa.Array] = {
            "scenario_id": pa.array([scenario_id] * n, pa.string()),
            "frame": pa.array(range(n), pa.int32()),
            "t_s": pa.array([float(m["t_s"]) for m in clock], pa.float64()),
            "ingest_id": pa.array([ingest_id] * n, pa.string()),
        }
        for name, (topic, field) in sources.items():
            typ = schema.field(name).type
            per_actor = _is_array_field(topic, field) and not pa.types.is_list(typ)
            columns[name] = _column(by_topic[topic], field, typ, per_actor, run.decoded)
    except RunRecordError:
        raise
    except KeyError as e:
        raise RunRecordError(f"message field {e} missing") from None
    except (ValueError, TypeError, IndexError, pa.ArrowException) as e:  # bad JSON or types
        raise RunRecordError(f"malformed message: {type(e).__name__}: {e}") from None
    _check_list_lengths(columns)
    return pa.table([columns[f.name] for f in schema], schema=schema)


def _same_lengths(a: pa.Array, b: pa.Array) -> bool:
    same = pc.equal(pc.list_value_length(a), pc.list_value_length(b))
    return bool(pc.all(same, min_count=0).as_py())


def _check_list_lengths(columns: dict[str, pa.Array]) -> None:
    """The per-item arrays of one message must have one entry per item (obstacle, point)."""
    for prefix in PREFIX_TOPIC:
        lists = [(n, c) for n, c in columns.items()
                 if n.startswith(prefix) and pa.types.is_list(c.type)]
        for name, col in lists[1:]:
            if not _same_lengths(col, lists[0][1]):
                raise RunRecordError(f"{name} and {lists[0][0]} differ in length in some frame")
        nested = [(n, c) for n, c in lists if pa.types.is_list(c.type.value_type)]
        for name, col in nested[1:]:
            if not _same_lengths(col.flatten(), nested[0][1].flatten()):
                raise RunRecordError(f"{name} and {nested[0][0]} differ in points per item")


def with_ingest_id(frames: pa.Table, ingest_id: str) -> pa.Table:
    """A frames table whose rows say they are in part `ingest_id`."""
    return frames.set_column(frames.schema.get_field_index("ingest_id"), "ingest_id",
                             pa.array([ingest_id] * frames.num_rows, pa.string()))


def frame_features_table(frames: pa.Table, spec: FeatureSpec = FEATURES, *,
                         features: FrameFeatures | None = None) -> pa.Table:
    """The frame_features rows of a frames table (file schema, same row order); `features`: its
    rows' features computed already (with `spec`)."""
    columns = pack(features if features is not None else frame_features(frames, spec))
    for name in ("scenario_id", "frame", "ingest_id"):
        columns[name] = frames.column(name)
    names = file_schema("frame_features").names  # the DDL's columns, with pack's list types
    return pa.table([columns[name] for name in names], names=names)


# topic → FrameMessages field, for the topics a live frame carries (not the ground truth, nor
# the ages of an imported recording)
TOPIC_ATTRIBUTE = {topic: name for topic, name in zip(TOPICS, TOPICS._fields, strict=True)
                   if name in FrameMessages.__dataclass_fields__}


def _plain(value: Any) -> Any:
    """A message value pyarrow converts as a (nested) list: 2-D arrays become lists of rows."""
    if isinstance(value, np.ndarray) and value.ndim > 1:
        return list(value)
    return value


def runtime_table(frames: Sequence[FrameMessages]) -> pa.Table:
    """The runtime columns of `frames` (live ADS messages, in time order) as the warehouse
    stores them, so `frame_features(runtime_table(...))` gives a monitor at runtime exactly the
    inputs it was trained on."""
    schema = file_schema("frames")
    columns: dict[str, pa.Array] = {
        "t_s": pa.array([f.localization.t_s for f in frames], pa.float64())
    }
    for name, (topic, field) in frame_column_sources().items():
        if topic in TOPIC_ATTRIBUTE:
            messages = [getattr(f, TOPIC_ATTRIBUTE[topic]) for f in frames]
            columns[name] = pa.array([_plain(getattr(m, field)) for m in messages],
                                     type=schema.field(name).type)
    return pa.table(columns)


def _stored_dtype(typ: pa.DataType) -> np.dtype:
    """The numpy type of a frames column's numbers (of its innermost items for a list)."""
    while pa.types.is_list(typ):
        typ = typ.value_type
    return np.dtype(typ.to_pandas_dtype()) if pa.types.is_floating(typ) else np.dtype(np.float64)


@cache
def _message_fields() -> dict[str, tuple[str, str, np.dtype]]:
    """Every runtime frames column → (FrameMessages attribute, message field, numpy type its
    numbers are stored as: a FLOAT column rounds to float32 in the warehouse, so here too)."""
    schema = file_schema("frames")
    return {name: (TOPIC_ATTRIBUTE[topic], field, _stored_dtype(schema.field(name).type))
            for name, (topic, field) in frame_column_sources().items() if topic in TOPIC_ATTRIBUTE}


class MessageSignals:
    """One frame's live ADS messages as feature `Signals` (evoeye.store.features): the values
    `runtime_table` would store, read straight from the messages (no Arrow on the way), so the
    monitor at run time computes its inputs with the warehouse's own feature code."""

    def __init__(self, messages: FrameMessages):
        self.messages = messages

    def __len__(self) -> int:
        return 1

    def _value(self, name: str) -> Any:
        attribute, field, _ = _message_fields()[name]
        return getattr(getattr(self.messages, attribute), field)

    def _numbers(self, name: str, value: Any) -> np.ndarray:
        """`value` as stored in column `name` (float32 for FLOAT), then as float64."""
        stored = np.asarray(value, _message_fields()[name][2])
        return stored if stored.dtype == np.float64 else stored.astype(np.float64)

    def scalar(self, name: str) -> np.ndarray:
        return self._numbers(name, (self._value(name),))

    def items(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        values = self._numbers(name, self._value(name)).reshape(-1)
        return np.array((0, len(values))), values

    def columns(self, names: tuple[str, ...]) -> tuple[np.ndarray, list[np.ndarray]]:
        fields = _message_fields()
        dtypes = {fields[name][2] for name in names}
        values = [self._value(name) for name in names]
        try:  # one conversion for the whole message when the columns share a type
            grid = np.array(values, dtypes.pop()) if len(dtypes) == 1 else None
        except ValueError:  # fields of unequal lengths
            grid = None
        if grid is None or grid.ndim != 2:
            return self.items(names[0])[0], [self.items(name)[1] for name in names]
        grid = grid.astype(np.float64, copy=False)
        return np.array((0, grid.shape[1])), list(grid)

    def points(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rows = self._value(name)
        try:  # (items, points): an array as the ADS sends it, or equal lists from a log
            grid = self._numbers(name, rows)
        except ValueError:  # lists of unequal lengths
            grid = None
        if grid is not None and grid.ndim == 2:
            counts = np.full(grid.shape[0], grid.shape[1])
            values = grid.reshape(-1)
        else:
            counts = np.array([len(r) for r in rows], np.int64)
            values = self._numbers(name, [v for r in rows for v in r])
        inner = np.zeros(len(counts) + 1, np.int64)
        np.cumsum(counts, out=inner[1:])
        return np.array((0, len(counts))), inner, values

    def codes(self, name: str, vocabulary: tuple[str, ...]) -> np.ndarray:
        value = self._value(name)
        return np.array((vocabulary.index(value) if value in vocabulary else -1,), np.int64)


def _check_partition(meta: dict[str, Any]) -> None:
    for key in PARTITION_KEYS:
        value = meta.get(key)
        if not isinstance(value, str) or not PARTITION_VALUE.match(value):
            raise RunRecordError(
                f"{key} = {value!r} cannot name a partition folder (letters, digits, . _ -)"
            )


def _finite_or_none(value: Any) -> float | None:
    return None if value is None or not math.isfinite(float(value)) else float(value)


def scenario_row(
    meta: dict[str, Any], *, n_frames: int, log_path: str, ingest_id: str, ingested_at: datetime
) -> dict[str, Any]:
    """The `scenarios` row of a run from its metadata, with partition keys (DDL order)."""
    _check_partition(meta)
    try:
        row = {
            "scenario_id": str(meta["scenario_id"]),
            "param_names": [str(p) for p in meta["param_names"]],
            "params": [float(v) for v in meta["params"]],
            "seed": int(meta["seed"]),
            "source": str(meta["source"]),
            "round": int(meta["round"]),
            "ads_profile": str(meta.get("ads_profile") or DEFAULT_PROFILE),
            "software_version": str(meta["software_version"]),
            "rate_hz": float(meta["rate_hz"]),
            "status": str(meta["status"]),
            "reason": str(meta["reason"] or ""),
            "collided": bool(meta["collided"]),
            "collision_time_s": _finite_or_none(meta["collision_time_s"]),
            "other_actor": None if meta["other_actor"] is None else int(meta["other_actor"]),
            "duration_s": float(meta["duration_s"]),
            "min_distance_m": _finite_or_none(meta["min_distance_m"]),
            "label_source": str(meta.get("label_source", SIMULATOR_LABELS)),
            "n_frames": int(n_frames),
            "log_path": log_path,
            "ingest_id": ingest_id,
            "ingested_at": ingested_at,
            "logical_scenario": str(meta["logical_scenario"]),
            "batch": str(meta["batch"]),
        }
    except KeyError as e:
        raise RunRecordError(f"run metadata has no {e}") from None
    except (TypeError, ValueError) as e:
        raise RunRecordError(f"run metadata has a malformed value: {e}") from None
    return {f.name: row[f.name] for f in table_schema("scenarios")}


def scenarios_table(rows: Sequence[dict[str, Any]]) -> pa.Table:
    """`scenarios` rows → Arrow in the Parquet file schema (partition keys dropped)."""
    schema = file_schema("scenarios")
    return pa.Table.from_pylist([{f.name: r[f.name] for f in schema} for r in rows], schema=schema)
