"""Episode → MCAP file, written atomically: a log either is complete or does not exist.
(`write_run`: the same for a run imported from another stack, from its channel messages.)

Layout: the `evoeye.run` metadata record, the `evoeye.road_map` attachment, one `/viz/map`
message at the first frame time, then per frame one message on each of the seven frame channels,
all at log time = publish time = simulation time. A supervised run's log (`Supervision`) adds the
`evoeye.supervisor` metadata record and per frame a message on /supervisor and /viz/supervisor.
Nothing depends on the wall clock, so the same episode always gives the same bytes.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import orjson
from mcap.writer import LIBRARY_IDENTIFIER

from evoeye import __version__
from evoeye.atomic import atomic_file
from evoeye.log.channels import (
    CHANNELS,
    FRAME_CHANNELS,
    MAP_CHANNEL,
    MESSAGE_ENCODING,
    ROAD_MAP_ATTACHMENT,
    RUN_RECORD,
    SCHEMA_ENCODING,
    SUPERVISOR_CHANNELS,
    SUPERVISOR_RECORD,
    Channel,
    log_time_ns,
)
from evoeye.log.mcap_writer import McapWriter
from evoeye.log.records import encode_run, road_map_dict, run_values
from evoeye.sim.episode import Episode
from evoeye.sim.supervisor import SupervisorState

# Chunk compression, chosen by measurement: CPU ms/frame of write_episode on 400 frames (best of
# 7, 2-core dev VM) and MB per run, for none / lz4 / zstd-1 / zstd-3:
#   synthetic worst case (6 obstacles, K=30, P=41, random 17-digit floats):
#     0.109 / 0.139 / 0.143 / 0.217 ms, 9.4 / 5.8 / 3.0 / 3.1 MB
#   a simulated highway-cut-in run: 0.104 / 0.118 / 0.124 / 0.150 ms, 6.7 / 2.5 / 1.35 / 1.46 MB
# zstd-1 costs ~5 µs/frame more than lz4 for half the bytes (half the disk writes and fsync);
# zstd-3, mcap's default (and not configurable in mcap.writer.Writer), breaks the 0.15 ms budget.
COMPRESSION = "zstd"
ZSTD_LEVEL = 1
CHUNK_SIZE_BYTES = 1024 * 1024
LIBRARY = f"evoeye/{__version__}; {LIBRARY_IDENTIFIER}"
_OPTIONS = orjson.OPT_SERIALIZE_NUMPY


@dataclass(frozen=True)
class Supervision:
    """What a supervised run's log adds (`evoeye supervise`): the supervisor's state per frame
    (channels /supervisor and /viz/supervisor) and a metadata record (trigger, thresholds,
    fallback), each value stored as its JSON text."""

    states: Sequence[SupervisorState]  # one per frame
    record: dict[str, Any]


def _fallback(value: Any) -> Any:
    """orjson's default: arrays it cannot take whole (non-contiguous, strings) become lists."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot serialise {type(value).__name__} to JSON")


def dumps(message: dict[str, Any]) -> bytes:
    """A message as compact JSON bytes (numpy arrays written whole; NaN and ±inf become null)."""
    return orjson.dumps(message, default=_fallback, option=_OPTIONS)


def _register(writer: McapWriter, channels: tuple[Channel, ...]) -> list[int]:
    """Register each schema once and each channel; the channel ids, in order."""
    schema_ids: dict[str, int] = {}
    channel_ids = []
    for channel in channels:
        if channel.schema_file not in schema_ids:
            schema_ids[channel.schema_file] = writer.register_schema(
                channel.schema_name, SCHEMA_ENCODING, orjson.dumps(channel.schema)
            )
        channel_ids.append(
            writer.register_channel(
                channel.topic, MESSAGE_ENCODING, schema_ids[channel.schema_file]
            )
        )
    return channel_ids


def write_stream(episode: Episode, stream: BinaryIO,
                 supervisor: Supervision | None = None) -> None:
    """Write the episode as MCAP to an open binary stream (no atomicity; see write_episode)."""
    writer = McapWriter(stream, COMPRESSION, ZSTD_LEVEL, CHUNK_SIZE_BYTES)
    writer.start(profile="", library=LIBRARY)
    extra = SUPERVISOR_CHANNELS if supervisor else ()
    map_id, *ids = _register(writer, (MAP_CHANNEL, *FRAME_CHANNELS, *extra))
    frame_ids, extra_ids = ids[: len(FRAME_CHANNELS)], ids[len(FRAME_CHANNELS):]
    writer.add_metadata(RUN_RECORD, encode_run(run_values(episode)))
    if supervisor:
        writer.add_metadata(SUPERVISOR_RECORD, {k: orjson.dumps(v).decode()
                                                for k, v in supervisor.record.items()})
    writer.add_attachment(
        create_time=0,  # the wall clock stays out: identical episodes give identical bytes
        log_time=0,
        name=ROAD_MAP_ATTACHMENT,
        media_type="application/json",
        data=dumps(road_map_dict(episode.road_map)),
    )
    t0_ns = log_time_ns(episode.frames[0].scene.t_s) if episode.frames else 0
    writer.add_message(map_id, t0_ns, dumps(MAP_CHANNEL.encode(episode.road_map, t0_ns)), t0_ns)
    # per frame channel: the message object orjson writes (`Channel.message`, no dict), else
    # its encoder's dict
    direct = [(ch.message, None) if ch.message else (None, ch.encode) for ch in FRAME_CHANNELS]
    extras = [ch.encode for ch in extra]
    ids, add = [*frame_ids, *extra_ids], writer.add_frame
    for seq, frame in enumerate(episode.frames):
        t_ns = log_time_ns(frame.scene.t_s)
        data = [dumps(message(frame) if message else encode(frame, t_ns))
                for message, encode in direct]
        if extras:
            data += [dumps(encode((frame, supervisor.states[seq]), t_ns)) for encode in extras]
        add(ids, t_ns, data, seq)
    writer.finish()


def write_run(metadata: dict[str, Any], frames: Sequence[dict[str, dict[str, Any]]],
              path: str | os.PathLike) -> Path:
    """Write a run that was not simulated here (an imported recording) atomically: its typed
    run metadata and, per frame, its channel messages by topic (evoeye's own channels, with
    the same messages in every frame). No road map or scene channel; the log time of a message
    is its frame's t_s."""
    topics = list(frames[0]) if frames else []
    unknown = [t for t in topics if t not in CHANNELS]
    if unknown:
        raise ValueError(f"no evoeye channel for topics {unknown}")
    path = Path(path)
    with atomic_file(path) as f:
        writer = McapWriter(f, COMPRESSION, ZSTD_LEVEL, CHUNK_SIZE_BYTES)
        writer.start(profile="", library=LIBRARY)
        ids = dict(zip(topics, _register(writer, tuple(CHANNELS[t] for t in topics)),
                       strict=True))
        writer.add_metadata(RUN_RECORD, encode_run(metadata))
        for seq, frame in enumerate(frames):
            t_ns = log_time_ns(frame[topics[0]]["t_s"])
            for topic in topics:
                writer.add_message(ids[topic], t_ns, dumps(frame[topic]), t_ns, seq)
        writer.finish()
    return path


def write_episode(episode: Episode, path: str | os.PathLike,
                  supervisor: Supervision | None = None) -> Path:
    """Write one run's log to `path` atomically and return the path.

    The bytes go to `<path>.<pid>@<host>.tmp` in the same folder, are flushed and fsynced, then
    renamed over `path`; on any error the temporary file is removed and the error re-raised, and
    a killed process leaves only a `.tmp` file, never a partial log under the final name. Failed
    runs (status "failed", possibly with zero frames) are written too, so their reason is on
    disk.
    """
    path = Path(path)
    with atomic_file(path) as f:
        write_stream(episode, f, supervisor)
    return path
