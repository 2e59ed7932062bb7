"""MCAP file → RunLog: the run's typed metadata, its road map and its messages per topic.

A file is read whole (a 20 s run is ~3 MB) and checked before anything is trusted: a
missing trailing magic means the writer never finished (a truncated copy); a bad leading magic
means it is not an MCAP file; chunk CRCs are verified. Every such problem is a LogError naming
the file, never a low-level parser exception.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import orjson
from mcap.reader import SeekingReader
from mcap.writer import MCAP0_MAGIC

from evoeye.log.channels import ROAD_MAP_ATTACHMENT, RUN_RECORD
from evoeye.log.chunks import channel_messages
from evoeye.log.records import decode_road_map, decode_run
from evoeye.scene import RoadMap

_MAGIC_SIZE = len(MCAP0_MAGIC)


class LogError(Exception):
    """A run log that cannot be read: missing, empty, truncated, corrupt or without its record."""


@dataclass
class RunLog:
    """One run log in memory. Messages are kept as raw JSON and decoded on first request."""

    path: Path
    metadata: dict[str, Any]  # typed by schemas/mcap/run.v1.json
    road_map: RoadMap | None
    raw: dict[str, list[tuple[int, bytes]]]  # topic -> [(log_time_ns, JSON bytes)], in time order
    schema_ids: dict[str, str]  # topic -> `$id` of its embedded schema, e.g. "…:localization.v1"
    requested: frozenset[str] | None = None  # the topics asked of read_run; None = all
    _decoded: dict[str, list[tuple[int, dict]]] = field(default_factory=dict, repr=False)
    decoded: ClassVar[bool] = True  # message values as JSON decodes them (lists, None)

    @property
    def topics(self) -> tuple[str, ...]:
        """The topics that were loaded (those requested that the file has, or all of them)."""
        return tuple(self.raw)

    def messages(self, topic: str) -> list[tuple[int, dict[str, Any]]]:
        """[(log_time_ns, message dict)] of a topic, in time order; [] if it has no messages."""
        if topic not in self._decoded:
            pairs = self._raw_pairs(topic)
            # Fast path: one orjson call over the topic as a JSON array, not one per message.
            try:
                dicts = orjson.loads(b"[" + b",".join(data for _, data in pairs) + b"]")
            except orjson.JSONDecodeError as e:
                raise _fail(self.path, f"a message on {topic} is not JSON ({e})") from e
            self._decoded[topic] = [(t, d) for (t, _), d in zip(pairs, dicts, strict=True)]
        return self._decoded[topic]

    def log_times_ns(self, topic: str) -> list[int]:
        """The log times of a topic's messages, in order."""
        return [t for t, _ in self._raw_pairs(topic)]

    def _raw_pairs(self, topic: str) -> list[tuple[int, bytes]]:
        if topic in self.raw:
            return self.raw[topic]
        if self.requested is None or topic in self.requested:
            return []  # requested (or everything was) but the file has no such messages
        raise KeyError(f"{self.path}: topic {topic!r} was not loaded; pass it to read_run")


def _fail(path: Path, problem: str) -> LogError:
    return LogError(f"{path}: {problem}")


def _check_framing(path: Path, data: bytes) -> None:
    if not data:
        raise _fail(path, "empty file")
    if len(data) < 2 * _MAGIC_SIZE or data[:_MAGIC_SIZE] != MCAP0_MAGIC:
        raise _fail(path, "not an MCAP file (bad leading magic)")
    if data[-_MAGIC_SIZE:] != MCAP0_MAGIC:
        raise _fail(path, "truncated MCAP file (no trailing magic: the writer did not finish)")


def _schema_ids(reader: SeekingReader) -> dict[str, str]:
    """topic -> `$id` of the channel's embedded JSON schema (its name when it has none)."""
    summary = reader.get_summary()
    if summary is None:
        raise ValueError("no summary section")
    ids = {}
    for channel in summary.channels.values():
        schema = summary.schemas.get(channel.schema_id)
        if schema is None:
            ids[channel.topic] = ""
        elif schema.encoding == "jsonschema":
            ids[channel.topic] = orjson.loads(schema.data).get("$id", schema.name)
        else:
            ids[channel.topic] = schema.name
    return ids


def read_run(path: str | os.PathLike, topics: Iterable[str] | None = None) -> RunLog:
    """Read a run log; only the given topics' messages are loaded (all when None).

    Raises LogError naming the file for a missing, empty, truncated or corrupt file, or one
    without a valid `evoeye.run` metadata record.
    """
    path = Path(path)
    wanted = None if topics is None else frozenset(topics)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise _fail(path, f"cannot read: {e.strerror or e}") from e
    _check_framing(path, data)
    try:
        reader = SeekingReader(io.BytesIO(data), validate_crcs=True)
        records = {m.name: m.metadata for m in reader.iter_metadata()}
        schema_ids = _schema_ids(reader)
        attachments = {a.name: a.data for a in reader.iter_attachments()}
        summary = reader.get_summary()  # _schema_ids checked there is one
        topic_of = {c.id: c.topic for c in summary.channels.values()
                    if wanted is None or c.topic in wanted}
        # the chunks walked directly (evoeye.log.chunks), not by mcap's per-record reader
        found = channel_messages(data, summary.chunk_indexes, topic_of) if topic_of else {}
        raw = {topic_of[c]: pairs for c, pairs in found.items() if pairs}
    except Exception as e:  # the mcap parser raises many kinds on corrupt input
        raise _fail(path, f"corrupt MCAP file ({type(e).__name__}: {e})") from e
    if RUN_RECORD not in records:
        raise _fail(path, f"no {RUN_RECORD!r} metadata record")
    try:
        metadata = decode_run(records[RUN_RECORD])
    except ValueError as e:
        raise _fail(path, f"invalid {RUN_RECORD!r} record: {e}") from e
    road_map = None
    if ROAD_MAP_ATTACHMENT in attachments:
        try:
            road_map = decode_road_map(attachments[ROAD_MAP_ATTACHMENT])
        except (ValueError, KeyError, TypeError) as e:
            raise _fail(path, f"invalid {ROAD_MAP_ATTACHMENT!r} attachment: {e}") from e
    for pairs in raw.values():
        pairs.sort(key=lambda p: p[0])  # stable: file order within one log time
    return RunLog(path, metadata, road_map, raw, schema_ids, wanted)
