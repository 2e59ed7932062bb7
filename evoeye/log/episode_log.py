"""An Episode as its log reads back, without the bytes: what `read_run` gives, from memory.

A run simulated and logged a moment ago need not be read back to be converted: `EpisodeLog`
answers what `RunLog` answers — the run record's typed metadata and each topic's messages in
log order — from the Episode itself. The metadata goes through the record's own encoding
(`encode_run` then `decode_run`), so it is exactly the log's. The messages are those the writer
encodes (`Channel.encode`), before JSON: numpy arrays where the log has lists, NaN and ±inf
where it has null (`decoded` is False). `evoeye.store.records.frames_table` turns either source
into the same frames (tests/store/test_episode_frames.py checks it).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from evoeye.log.channels import CHANNELS, FRAME_CHANNELS, MAP_CHANNEL, OPTIONAL_TOPICS, log_time_ns
from evoeye.log.records import decode_run, encode_run, run_values
from evoeye.sim.episode import Episode

_FRAME_TOPICS = frozenset(c.topic for c in FRAME_CHANNELS)


class EpisodeLog:
    """The log of `episode` (written at `path`) as `read_run` would give it, from memory."""

    decoded = False  # message values as published (numpy, NaN), not as JSON decodes them

    def __init__(self, episode: Episode, path: str | Path) -> None:
        self.episode = episode
        self.path = Path(path)
        self.metadata: dict[str, Any] = decode_run(encode_run(run_values(episode)))
        self._messages: dict[str, list[tuple[int, dict[str, Any]]]] = {}

    def messages(self, topic: str) -> list[tuple[int, dict[str, Any]]]:
        """[(log_time_ns, message dict)] of a topic, in time order; [] if it has no messages."""
        if topic not in CHANNELS or topic in OPTIONAL_TOPICS:  # a simulation has none
            return []
        if topic not in self._messages:
            self._messages[topic] = self._encode(topic)
        return self._messages[topic]

    def _encode(self, topic: str) -> list[tuple[int, dict[str, Any]]]:
        frames = self.episode.frames
        if topic in _FRAME_TOPICS:
            encode = CHANNELS[topic].encode
            times = [log_time_ns(f.scene.t_s) for f in frames]
            return [(t, encode(f, t)) for t, f in zip(times, frames, strict=True)]
        t0 = log_time_ns(frames[0].scene.t_s) if frames else 0  # the writer's map message
        return [(t0, MAP_CHANNEL.encode(self.episode.road_map, t0))]
