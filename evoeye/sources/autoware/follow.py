"""Follow a rosbag2 MCAP while it is being recorded (or a folder of split bags), without ROS.

The file is read as it grows: only whole records are parsed (a partial trailing record waits
for the next poll), chunks are opened as they land, and messages come out in file order —
the receive order `FrameAssembler` wants. Record with `--storage-config-file` holding
`noChunking: true` (docs/autoware.md) and each message is on disk at once; with chunking a
message waits for its chunk (about 1 MB). CDR is decoded with rosbags, by the definitions the
file embeds, as `evoeye import` decodes it (`typestore.bag_typestore`: the vendored Autoware and
ROS 2 Humble types only for a file that embeds none). A message that does not decode, or a file
that is not MCAP, is a `SourceError` naming the topic. In a folder of split bags
(`<name>_0.mcap`, `<name>_1.mcap`, …) a file is finished when the next one appears.
"""

from __future__ import annotations

import io
import re
import struct
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from mcap.exceptions import EndOfFile
from mcap.records import Channel, Footer, Message, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import MCAP0_MAGIC

from evoeye.sources.autoware.frames import SourceError
from evoeye.sources.autoware.typestore import bag_typestore

_HEAD = struct.Struct("<BQ")  # opcode, record length
SPLIT_INDEX = re.compile(r"_(\d+)\.mcap$")
Decoded = tuple[str, str, Any, int]  # topic, type name, message, log time ns


class McapFollower:
    """Incremental reader of one MCAP file; `poll()` returns the messages completed since."""

    def __init__(self, path: Path, topics: set[str] | None = None):
        self.path = path
        self.topics = topics  # decode only these (None: all)
        self.offset = 0  # bytes of whole records consumed
        self.finished = False  # the footer was read
        self._channels: dict[int, tuple[str, str]] = {}  # channel id → (topic, type name)
        self._schemas: dict[int, Schema] = {}
        self._store = None

    def _typestore(self) -> Any:
        if self._store is None:
            self._store = bag_typestore((s.name, s.encoding, s.data.decode())
                                        for s in self._schemas.values())
        return self._store

    def _complete(self, data: bytes) -> int:
        """Length of the whole records at the start of `data`."""
        end = 0
        while end + _HEAD.size <= len(data):
            _, length = _HEAD.unpack_from(data, end)
            if end + _HEAD.size + length > len(data):
                break
            end += _HEAD.size + length
        return end

    def poll(self) -> list[Decoded]:
        if self.finished:
            return []
        with open(self.path, "rb") as f:
            f.seek(self.offset)
            data = f.read()
        if self.offset == 0:
            if len(data) < len(MCAP0_MAGIC):
                return []
            if data[: len(MCAP0_MAGIC)] != MCAP0_MAGIC:
                raise SourceError("(bag)", "not an MCAP file (bad leading magic)")
            data = data[len(MCAP0_MAGIC):]
            self.offset = len(MCAP0_MAGIC)
        end = self._complete(data)
        if end == 0:
            return []
        self.offset += end
        out: list[Decoded] = []
        records = StreamReader(io.BytesIO(data[:end]), skip_magic=True).records
        try:
            for record in records:
                self._take(record, out)
        except EndOfFile:
            pass  # the end of the whole records read this time
        return out

    def _take(self, record: Any, out: list[Decoded]) -> None:
        if isinstance(record, Schema):
            self._schemas[record.id] = record
            self._store = None  # a new definition: rebuild the store on the next message
        elif isinstance(record, Channel):
            schema = self._schemas.get(record.schema_id)
            self._channels[record.id] = (record.topic, schema.name if schema else "")
        elif isinstance(record, Message):
            topic, msgtype = self._channels.get(record.channel_id, ("", ""))
            if self.topics is None or topic in self.topics:
                try:
                    msg = self._typestore().deserialize_cdr(record.data, msgtype)
                except Exception as e:  # rosbags raises several kinds on bytes it cannot read
                    raise SourceError(topic, f"cannot decode {msgtype} "
                                             f"({type(e).__name__}: {e})") from None
                out.append((topic, msgtype, msg, record.log_time))
        elif isinstance(record, Footer):
            self.finished = True


def _split_files(folder: Path) -> list[Path]:
    files = list(folder.glob("*.mcap"))
    return sorted(files, key=lambda p: (int(m.group(1)) if (m := SPLIT_INDEX.search(p.name))
                                        else -1, p.name))


def follow(path: Path, *, topics: set[str] | None = None, poll_s: float = 0.005,
           idle_s: float = 5.0, sleep: Callable[[float], None] = time.sleep,
           follower: Callable[[Path, set[str] | None], Any] = McapFollower,
           split_files: Callable[[Path], list[Path]] = _split_files) -> Iterator[Decoded]:
    """The messages of a growing MCAP file (or folder of split bags), in file order; ends when
    the (last) file is finished and nothing new appears for `idle_s`, or stays idle that long.
    Another format: its `follower` (with `poll()`, `path`, `finished`) and `split_files`."""
    done: list[Path] = []
    current: Any = None
    idle_since = time.monotonic()
    while True:
        files = split_files(path) if path.is_dir() else ([path] if path.exists() else [])
        pending = [f for f in files if f not in done]
        if current is None and pending:
            current = follower(pending[0], topics)
        got = current.poll() if current is not None else []
        yield from got
        if current is not None and not got:
            newer = [f for f in pending if f != current.path]
            if current.finished or newer:
                got = current.poll()  # whatever landed before the next file started
                yield from got
                done.append(current.path)
                current = None
                if newer:
                    continue
        if got:
            idle_since = time.monotonic()
        elif time.monotonic() - idle_since > idle_s:
            return
        else:
            sleep(poll_s)
