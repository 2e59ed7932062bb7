"""Follow a cyber record while it is being written (or a folder of split records), for
`evoeye watch`: whole sections only (a cut one waits for the next poll), messages as their
chunk lands. Apollo's recorder writes a chunk every `chunk_interval` (20 s by default) or
`chunk_raw_size`, so a message reaches the file — and the monitor — only with its chunk:
record with a short chunk interval to watch live. The index section, written on close, ends
the file; split records (`x.record.00000`, `x.record.00001`, …) are followed in order.
"""

from __future__ import annotations

import re
from pathlib import Path

from evoeye.sources.apollo.protos import classes_from_proto_desc, record_type, vendored
from evoeye.sources.apollo.record import (
    CHANNEL,
    CHUNK_BODY,
    HEADER,
    HEADER_LENGTH,
    INDEX,
    SECTION,
    RecordError,
    decompress,
)
from evoeye.sources.autoware.follow import Decoded
from evoeye.sources.autoware.frames import SourceError

SPLIT_SUFFIX = re.compile(r"\.record(?:\.(\d+))?$")


def is_record(path: Path) -> bool:
    """Whether `path` is a cyber record, or a folder holding some."""
    if path.is_dir():
        return bool(record_splits(path))
    return SPLIT_SUFFIX.search(path.name) is not None


def record_splits(folder: Path) -> list[Path]:
    """The records of a folder, in split order."""
    found = [(p, m) for p in folder.iterdir() if (m := SPLIT_SUFFIX.search(p.name))]
    return [p for p, _ in sorted(found, key=lambda pm: (int(pm[1].group(1) or -1), pm[0].name))]


class RecordFollower:
    """Incremental reader of one cyber record; `poll()` returns the messages landed since."""

    def __init__(self, path: Path, topics: set[str] | None = None) -> None:
        self.path = path
        self.topics = topics
        self.offset = 0  # bytes of whole sections consumed
        self.finished = False  # the index was read
        self.compress = 0
        self.classes: dict[str, tuple[str, type]] = {}  # channel → (type, class)

    def poll(self) -> list[Decoded]:
        if self.finished:
            return []
        with open(self.path, "rb") as f:
            f.seek(self.offset)
            data = f.read()
        pos, out = 0, []
        if self.offset == 0:
            if len(data) < SECTION.size + HEADER_LENGTH:
                return []
            kind, size = SECTION.unpack_from(data)
            if kind != HEADER:
                raise SourceError("(record)", f"not a cyber record (first section of type "
                                              f"{kind})")
            header = record_type("Header").FromString(data[SECTION.size:SECTION.size + size])
            self.compress = header.compress
            pos = SECTION.size + HEADER_LENGTH
        while pos + SECTION.size <= len(data):
            kind, size = SECTION.unpack_from(data, pos)
            if pos + SECTION.size + size > len(data):
                break  # being written
            self._take(kind, data[pos + SECTION.size: pos + SECTION.size + size], out)
            pos += SECTION.size + size
        self.offset += pos
        return out

    def _take(self, kind: int, body: bytes, out: list[Decoded]) -> None:
        if kind == CHANNEL:
            c = record_type("Channel").FromString(body)
            own = classes_from_proto_desc(c.proto_desc) if c.proto_desc else {}
            cls = own.get(c.message_type) or vendored().get(c.message_type)
            self.classes[c.name] = (c.message_type, cls)
        elif kind == CHUNK_BODY:
            try:
                raw = decompress(body, self.compress)
            except RecordError as e:
                raise SourceError("(record)", str(e)) from None
            for m in record_type("ChunkBody").FromString(raw).messages:
                if self.topics is not None and m.channel_name not in self.topics:
                    continue
                msgtype, cls = self.classes.get(m.channel_name, ("", None))
                if cls is None:
                    raise SourceError(m.channel_name, f"no definition of {msgtype or 'its type'}")
                try:
                    msg = cls.FromString(m.content)
                except Exception as e:  # protobuf's DecodeError on damaged bytes
                    raise SourceError(m.channel_name, f"cannot decode {msgtype} "
                                                      f"({type(e).__name__}: {e})") from None
                out.append((m.channel_name, msgtype, msg, m.time))
        elif kind == INDEX:
            self.finished = True
