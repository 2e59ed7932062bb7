"""Replay a run log through a monitor: a copy of the log with its risk and alarms added.

The copy keeps every record of the original (schemas, channels, messages, the run metadata and
the road-map attachment) and adds, per frame, at the frame's log time:

    /monitor/risk   evoeye.MonitorRisk (schemas/mcap/monitor_risk.v1.json): t_s, score, alarm,
                    threshold, monitor_version
    /viz/monitor    foxglove.SceneUpdate: the score as text above the ego (red while the alarm is
                    on) and, during an alarm, a red box around the ego

so Foxglove or Lichtblick show the warning next to the scene. Frames are streamed through the
RuntimeMonitor, so a replay shows what the monitor would have said live. Replaying a replayed
log replaces its monitor channels. The copy is written atomically.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcap.reader import SeekingReader

from evoeye.ads.messages import (
    ControlCommand,
    FrameMessages,
    Localization,
    Obstacles,
    PlannedTrajectory,
    Predictions,
)
from evoeye.atomic import atomic_file
from evoeye.log import TOPICS, read_run
from evoeye.log.channels import MESSAGE_ENCODING, SCHEMA_ENCODING, load_schema, log_time_ns
from evoeye.log.mcap_writer import McapWriter
from evoeye.log.viz import ego_label
from evoeye.log.writer import CHUNK_SIZE_BYTES, COMPRESSION, LIBRARY, ZSTD_LEVEL, dumps
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.protocol import WARNING_K
from evoeye.monitor.runtime import RiskState, RuntimeMonitor

RISK_TOPIC = "/monitor/risk"
VIZ_TOPIC = "/viz/monitor"
RISK_SCHEMA_FILE = "monitor_risk.v1.json"
VIZ_SCHEMA_FILE = "scene_update.v1.json"
MESSAGE_TYPES = (  # FrameMessages field, topic, message type
    ("localization", TOPICS.localization, Localization),
    ("obstacles", TOPICS.obstacles, Obstacles),
    ("predictions", TOPICS.predictions, Predictions),
    ("plan", TOPICS.plan, PlannedTrajectory),
    ("control", TOPICS.control, ControlCommand),
)


@dataclass(frozen=True)
class ReplayReport:
    """Where the copy went, what the monitor said, and when the run collided."""

    out: Path
    frames: int
    alarm_frames: int
    first_alarm_t_s: float | None
    threshold: float
    collision_t_s: float | None = None  # the run's first collision (None: it never collided)

    @property
    def warning_t_s(self) -> float | None:
        """The first alarm before the collision (any first alarm in a run without one)."""
        t = self.first_alarm_t_s
        if t is None or (self.collision_t_s is not None and t >= self.collision_t_s):
            return None
        return t

    @property
    def lead_s(self) -> float | None:
        """How long before the collision the monitor warned (None: no collision or no
        warning before it)."""
        if self.collision_t_s is None or self.warning_t_s is None:
            return None
        return self.collision_t_s - self.warning_t_s

    def words(self) -> str:
        """The run's outcome and the monitor's warning in one sentence."""
        if self.collision_t_s is None:
            said = ("no alarm" if self.first_alarm_t_s is None
                    else f"a false alarm at t = {self.first_alarm_t_s:.2f} s")
            return f"no collision; {said}"
        hit = f"collision at t = {self.collision_t_s:.2f} s"
        if self.lead_s is None:
            return f"{hit}; no alarm before it (missed)"
        return (f"{hit}; first alarm at t = {self.warning_t_s:.2f} s, {self.lead_s:.2f} s "
                "before it")


def log_frames(path: str | os.PathLike) -> list[FrameMessages]:
    """The ADS module messages of every frame of a run log, as the warehouse reads them
    (field values as decoded from JSON: lists where the dataclasses hold arrays)."""
    run = read_run(path, topics=[topic for _, topic, _ in MESSAGE_TYPES])
    per_topic = {name: [msg for _, msg in run.messages(topic)]
                 for name, topic, _ in MESSAGE_TYPES}
    counts = {len(msgs) for msgs in per_topic.values()}
    if len(counts) != 1:
        raise ValueError(f"{path}: the ADS topics have different message counts "
                         f"{ {n: len(m) for n, m in per_topic.items()} }")
    types = {name: cls for name, _, cls in MESSAGE_TYPES}
    return [
        FrameMessages(**{name: types[name](**msgs[i]) for name, msgs in per_topic.items()})
        for i in range(counts.pop())
    ]


def risk_message(state: RiskState, version: str) -> dict[str, Any]:
    """The /monitor/risk message of one frame."""
    return {"t_s": state.t_s, "score": state.score, "alarm": state.alarm,
            "threshold": state.threshold, "monitor_version": version}


def marker_update(state: RiskState, ego: Localization, t_ns: int) -> dict[str, Any]:
    """The /viz/monitor SceneUpdate of one frame: score text, and a red box while alarming."""
    return ego_label(t_ns, ego.x_m, ego.y_m, ego.heading_rad,
                     f"{'ALARM ' if state.alarm else ''}risk {state.score:.2f}", state.alarm,
                     ("monitor/risk", "monitor/alarm"))


def _write_copy(source: bytes, stream: io.BufferedWriter,
                added: list[tuple[int, str, bytes]]) -> None:
    """Copy every record of the MCAP `source`, merging in `added` = [(log ns, topic, data)]
    (in time order) after the original messages of the same log time."""
    reader = SeekingReader(io.BytesIO(source))
    summary = reader.get_summary()
    writer = McapWriter(stream, COMPRESSION, ZSTD_LEVEL, CHUNK_SIZE_BYTES)
    writer.start(profile=reader.get_header().profile, library=LIBRARY)
    schema_ids = {sid: writer.register_schema(s.name, s.encoding, s.data)
                  for sid, s in sorted(summary.schemas.items())}
    ours = {RISK_TOPIC, VIZ_TOPIC}
    channel_ids = {cid: writer.register_channel(c.topic, c.message_encoding,
                                                schema_ids[c.schema_id])
                   for cid, c in sorted(summary.channels.items()) if c.topic not in ours}
    by_name = {s.name: schema_ids[sid] for sid, s in summary.schemas.items()}
    new_ids: dict[str, int] = {}
    for topic, schema_file in ((RISK_TOPIC, RISK_SCHEMA_FILE), (VIZ_TOPIC, VIZ_SCHEMA_FILE)):
        schema = load_schema(schema_file)
        sid = by_name.get(schema["title"])
        if sid is None:
            sid = writer.register_schema(schema["title"], SCHEMA_ENCODING, dumps(schema))
        new_ids[topic] = writer.register_channel(topic, MESSAGE_ENCODING, sid)
    for record in reader.iter_metadata():
        writer.add_metadata(record.name, record.metadata)
    for a in reader.iter_attachments():
        writer.add_attachment(a.create_time, a.log_time, a.name, a.media_type, a.data)
    pending = iter(added)
    nxt = next(pending, None)
    seq = 0
    for _, channel, message in reader.iter_messages(log_time_order=False):
        while nxt is not None and nxt[0] < message.log_time:
            writer.add_message(new_ids[nxt[1]], nxt[0], nxt[2], nxt[0], seq)
            nxt = next(pending, None)
        if channel.id in channel_ids:
            writer.add_message(channel_ids[channel.id], message.log_time, message.data,
                               message.publish_time, message.sequence)
        seq = message.sequence
    while nxt is not None:
        writer.add_message(new_ids[nxt[1]], nxt[0], nxt[2], nxt[0], seq)
        nxt = next(pending, None)
    writer.finish()


def replay(log: str | os.PathLike, monitor: FusionMonitor, out: str | os.PathLike | None = None,
           *, fpr: float = 0.05, consecutive: int = WARNING_K) -> ReplayReport:
    """Write a copy of `log` with the monitor's risk and alarm channels (default
    `<log>.risk.mcap` beside it); what the monitor said."""
    log = Path(log)
    out = Path(out) if out is not None else log.with_name(f"{log.stem}.risk.mcap")
    if out.resolve() == log.resolve():
        raise ValueError(f"the replay must not overwrite its source log {log}")
    frames = log_frames(log)
    meta = read_run(log, topics=()).metadata
    collision_t = meta.get("collision_time_s") if meta.get("collided") else None
    runtime = RuntimeMonitor(monitor, fpr=fpr, consecutive=consecutive)
    states = runtime.run(frames)
    added: list[tuple[int, str, bytes]] = []
    for state, frame in zip(states, frames, strict=True):
        t_ns = log_time_ns(state.t_s)
        added.append((t_ns, RISK_TOPIC, dumps(risk_message(state, monitor.version))))
        added.append((t_ns, VIZ_TOPIC, dumps(marker_update(state, frame.localization, t_ns))))
    with atomic_file(out) as f:
        _write_copy(log.read_bytes(), f, added)
    alarm_t = [s.t_s for s in states if s.alarm]
    return ReplayReport(out, len(states), len(alarm_t), alarm_t[0] if alarm_t else None,
                        runtime.threshold, None if collision_t is None else float(collision_t))
