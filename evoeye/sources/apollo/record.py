"""A cyber `.record` file (Apollo's recorder format, version 1.0), read and written in Python.

The file is a sequence of sections, each a 16-byte head (type as int32, 4 bytes padding, size
as int64, little-endian) and a protobuf body (cyber/proto/record.proto):

    HEADER       at 0, its body padded to HEADER_LENGTH; `is_complete` once the writer closed
    CHANNEL      a channel's name, message type and ProtoDesc (its descriptors), before its
                 first message
    CHUNK_HEADER begin and end time and message count of the chunk body after it
    CHUNK_BODY   the messages (channel name, time ns, serialized bytes), in time order
    INDEX        at the end, where the header's `index_position` points

`read_record` scans the sections in order (the index is not needed), so a record being written
reads up to its last whole section. `RecordError` names what is wrong in one line.
"""

from __future__ import annotations

import bz2
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from evoeye.sources.apollo.protos import proto_desc, record_type

HEADER_LENGTH = 2048
SECTION = struct.Struct("<i4xq")  # type, padding, size
HEADER, CHUNK_HEADER, CHUNK_BODY, INDEX, CHANNEL = range(5)  # SectionType
COMPRESS_NONE, COMPRESS_BZ2, COMPRESS_LZ4 = range(3)


class RecordError(ValueError):
    """A record that cannot be read: one line naming the problem (the caller names the file)."""


@dataclass(frozen=True)
class Channel:
    name: str
    message_type: str  # full protobuf name, e.g. apollo.localization.LocalizationEstimate
    proto_desc: bytes  # cyber ProtoDesc: the type's file descriptor and its imports'


@dataclass
class Record:
    """What `read_record` found: the header, the channels and the raw messages in file order."""

    header: Any
    channels: dict[str, Channel] = field(default_factory=dict)
    messages: list[tuple[str, int, bytes]] = field(default_factory=list)  # (channel, ns, bytes)


def _sections(data: bytes) -> Iterator[tuple[int, bytes]]:
    """(type, body) of each whole section; RecordError for a cut one."""
    pos = 0
    while pos < len(data):
        if pos + SECTION.size > len(data):
            raise RecordError(f"truncated: a section head cut at byte {pos}")
        kind, size = SECTION.unpack_from(data, pos)
        body = data[pos + SECTION.size: pos + SECTION.size + size]
        if len(body) < size or size < 0:
            raise RecordError(f"truncated: a section of {size} bytes at byte {pos} holds "
                              f"{len(body)}")
        yield kind, body
        pos += SECTION.size + (HEADER_LENGTH if kind == HEADER else size)


def read_record(path: str | Path) -> Record:
    """Every channel and message of a cyber record; RecordError if it cannot be read."""
    data = Path(path).read_bytes()
    if not data:
        raise RecordError("empty file")
    header_cls, channel_cls, body_cls = (record_type(n) for n in ("Header", "Channel",
                                                                    "ChunkBody"))
    sections = _sections(data)
    try:
        kind, body = next(sections)
        if kind != HEADER:
            raise RecordError(f"not a cyber record (first section of type {kind})")
        header = header_cls.FromString(body)
        if header.major_version != 1:
            raise RecordError(f"record version {header.major_version}.{header.minor_version} "
                              "(1.x is read)")
        record = Record(header)
        for kind, body in sections:
            if kind == CHANNEL:
                c = channel_cls.FromString(body)
                record.channels[c.name] = Channel(c.name, c.message_type, c.proto_desc)
            elif kind == CHUNK_BODY:
                raw = decompress(body, header.compress)
                record.messages += [(m.channel_name, m.time, m.content)
                                    for m in body_cls.FromString(raw).messages]
            elif kind not in (CHUNK_HEADER, INDEX):
                raise RecordError(f"unknown section type {kind}")
    except RecordError:
        raise
    except Exception as e:  # protobuf's DecodeError and kin, on damaged bytes
        raise RecordError(f"unreadable ({type(e).__name__}: {e})") from None
    return record


def decompress(body: bytes, compress: int) -> bytes:
    if compress == COMPRESS_NONE:
        return body
    if compress == COMPRESS_BZ2:
        return bz2.decompress(body)
    raise RecordError("LZ4-compressed chunks are not read (record with compression off or bz2)")


def write_record(path: str | Path, messages: list[tuple[str, int, Any]],
                 chunk_messages: int = 1000) -> Path:
    """Write [(channel, time ns, protobuf message)] (time-sorted) as a complete cyber record,
    each channel with its type's vendored descriptors; written beside `path`, then renamed."""
    path = Path(path)
    header_cls = record_type("Header")
    header = header_cls(major_version=1, minor_version=0, compress=COMPRESS_NONE,
                        chunk_interval=20_000_000_000, segment_interval=60_000_000_000,
                        chunk_raw_size=200 * 1024 * 1024, segment_raw_size=2048 * 1024 * 1024)
    out = bytearray(SECTION.size + HEADER_LENGTH)  # the header, written last
    index = record_type("Index")()

    def section(kind: int, msg: Any) -> None:
        body = msg.SerializeToString()
        position = len(out)
        out.extend(SECTION.pack(kind, len(body)) + body)
        if kind == INDEX:
            return
        entry = index.indexes.add(type=kind, position=position)
        if kind == CHANNEL:
            entry.channel_cache.name = msg.name
            entry.channel_cache.message_type = msg.message_type
            entry.channel_cache.proto_desc = msg.proto_desc
        elif kind == CHUNK_HEADER:
            entry.chunk_header_cache.message_number = msg.message_number
            entry.chunk_header_cache.begin_time = msg.begin_time
            entry.chunk_header_cache.end_time = msg.end_time
        elif kind == CHUNK_BODY:
            entry.chunk_body_cache.message_number = len(msg.messages)

    channels: dict[str, Any] = {}
    for start in range(0, len(messages), chunk_messages):
        chunk = messages[start:start + chunk_messages]
        body = record_type("ChunkBody")()
        for name, t_ns, msg in chunk:
            if name not in channels:
                kind = msg.DESCRIPTOR.full_name
                channels[name] = record_type("Channel")(name=name, message_type=kind,
                                                        proto_desc=proto_desc(kind))
                section(CHANNEL, channels[name])
            body.messages.add(channel_name=name, time=t_ns, content=msg.SerializeToString())
        section(CHUNK_HEADER, record_type("ChunkHeader")(
            begin_time=chunk[0][1], end_time=chunk[-1][1], message_number=len(chunk),
            raw_size=body.ByteSize()))
        section(CHUNK_BODY, body)
        header.chunk_number += 1
    header.index_position = len(out)
    for c in channels.values():  # the index holds each channel's message count too
        n = sum(1 for m in messages if m[0] == c.name)
        next(i for i in index.indexes if i.type == CHANNEL and i.channel_cache.name == c.name
             ).channel_cache.message_number = n
    section(INDEX, index)
    header.channel_number = len(channels)
    header.message_number = len(messages)
    header.begin_time = messages[0][1] if messages else 0
    header.end_time = messages[-1][1] if messages else 0
    header.size = len(out)
    header.is_complete = True
    head = header.SerializeToString()
    out[:SECTION.size + len(head)] = SECTION.pack(HEADER, len(head)) + head
    tmp = path.with_name(f".{path.name}.partial")
    tmp.write_bytes(bytes(out))
    tmp.replace(path)
    return path
