"""The runtime monitor beside a running stack: frames in as they are assembled, risk out.

Each frame (evoeye channel messages, e.g. from `evoeye.sources.autoware.frames`) goes through
the RuntimeMonitor (ONNX Runtime, the warehouse's feature code), and its risk is written
(`RiskSink`) as one JSON line — `{"t_s", "score", "alarm", "threshold", "monitor_version"}`,
the /monitor/risk message `evoeye replay` writes — and into an MCAP with the /monitor/risk
channel (Plot `.score` and `.threshold`, State Transitions `.alarm` in Foxglove) plus a
`foxglove.Log` on /monitor/log at each alarm onset. The MCAP is written in small chunks, so a
viewer opening it while the monitor runs sees all but the last second or so; it is complete
once the watch ends.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

from evoeye.ads.messages import FrameMessages
from evoeye.log.channels import MESSAGE_ENCODING, SCHEMA_ENCODING, load_schema
from evoeye.log.mcap_writer import McapWriter
from evoeye.log.viz import stamp
from evoeye.log.writer import LIBRARY, dumps
from evoeye.monitor.replay import MESSAGE_TYPES, RISK_SCHEMA_FILE, RISK_TOPIC, risk_message
from evoeye.monitor.runtime import RiskState, RuntimeMonitor

LOG_TOPIC = "/monitor/log"
LOG_SCHEMA = {  # foxglove.Log (docs.foxglove.dev, schemas/log), as JSON Schema
    "title": "foxglove.Log", "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {"sec": {"type": "integer"},
                                                       "nsec": {"type": "integer"}}},
        "level": {"type": "integer"}, "message": {"type": "string"},
        "name": {"type": "string"}, "file": {"type": "string"}, "line": {"type": "integer"},
    },
}
LOG_WARNING = 3
CHUNK_BYTES = 4096  # small chunks: the MCAP is readable while it grows


def frame_messages(messages: dict[str, dict[str, Any]]) -> FrameMessages:
    """A frame's evoeye channel messages (by topic) as the ADS's FrameMessages."""
    return FrameMessages(**{name: cls(**messages[topic]) for name, topic, cls in MESSAGE_TYPES})


class RiskSink:
    """Writes each frame's risk to a JSON-lines callback and to a risk MCAP stream."""

    def __init__(self, stream: BinaryIO, emit: Callable[[bytes], None], version: str):
        self.emit = emit
        self.version = version
        self.writer = McapWriter(stream, "zstd", 1, CHUNK_BYTES)
        self.writer.start(profile="", library=LIBRARY)
        risk = load_schema(RISK_SCHEMA_FILE)
        self.risk_id = self.writer.register_channel(RISK_TOPIC, MESSAGE_ENCODING,
                                                    self.writer.register_schema(
                                                        risk["title"], SCHEMA_ENCODING,
                                                        dumps(risk)))
        self.log_id = self.writer.register_channel(LOG_TOPIC, MESSAGE_ENCODING,
                                                   self.writer.register_schema(
                                                       "foxglove.Log", SCHEMA_ENCODING,
                                                       dumps(LOG_SCHEMA)))
        self.alarming = False
        self.seq = 0

    def write(self, state: RiskState, t_ns: int) -> None:
        data = dumps(risk_message(state, self.version))
        self.emit(data)
        self.writer.add_message(self.risk_id, t_ns, data, t_ns, self.seq)
        if state.alarm and not self.alarming:
            log = {"timestamp": stamp(t_ns), "level": LOG_WARNING, "name": "evoeye",
                   "message": f"collision risk {state.score:.2f} over {state.threshold:.2f}",
                   "file": "", "line": 0}
            self.writer.add_message(self.log_id, t_ns, dumps(log), t_ns, self.seq)
        self.alarming = state.alarm
        self.seq += 1

    def close(self) -> None:
        self.writer.finish()


class Watch:
    """Scores frames one at a time and writes their risk (`step`); `close()` at the end."""

    def __init__(self, runtime: RuntimeMonitor, out: str | os.PathLike,
                 emit: Callable[[bytes], None]):
        self.runtime = runtime
        self.path = Path(out)
        self._file = open(self.path, "wb")  # noqa: SIM115 - closed by close()
        self.sink = RiskSink(self._file, emit, runtime.monitor.version)
        self.states: list[RiskState] = []

    def step(self, messages: dict[str, dict[str, Any]], t_ns: int) -> RiskState:
        state = self.runtime.step(frame_messages(messages))
        self.sink.write(state, t_ns)
        self.states.append(state)
        return state

    def close(self) -> None:
        self.sink.close()
        self._file.close()

