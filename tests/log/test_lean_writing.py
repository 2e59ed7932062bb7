"""The log's fast path (frames added whole, message objects serialised without a dict, arrays
written whole) writes what the plain path writes: mcap's own Writer fed one encoded dict per
message gives the same bytes, so no reader can tell them apart."""

from __future__ import annotations

import io

import numpy as np
import orjson
import pytest
from mcap.writer import CompressionType, Writer

from evoeye.batch import plan_uniform
from evoeye.log import writer as log_writer
from evoeye.log.channels import (
    FRAME_CHANNELS,
    MAP_CHANNEL,
    ROAD_MAP_ATTACHMENT,
    RUN_RECORD,
    log_time_ns,
)
from evoeye.log.records import encode_run, road_map_dict, run_values
from evoeye.log.synthetic import synthetic_episode
from evoeye.sim.episode import Episode
from evoeye.sim.runner import run_episode

SIM_TOPICS = {"/ads/perception/obstacles", "/sim/ground_truth"}  # arrays built by the stack


@pytest.fixture(scope="module")
def simulated() -> Episode:
    spec = plan_uniform("highway-cut-in", 1, seed=7)[0]
    return run_episode(spec)


def plain_log(episode: Episode) -> bytes:
    """The log as mcap's Writer writes it (zstd at its fixed level 3), one dict per message."""
    out = io.BytesIO()
    writer = Writer(out, chunk_size=log_writer.CHUNK_SIZE_BYTES, compression=CompressionType.ZSTD)
    writer.start(profile="", library=log_writer.LIBRARY)
    schema_ids: dict[str, int] = {}
    ids = []
    for channel in (MAP_CHANNEL, *FRAME_CHANNELS):
        if channel.schema_file not in schema_ids:
            schema_ids[channel.schema_file] = writer.register_schema(
                channel.schema_name, "jsonschema", orjson.dumps(channel.schema))
        ids.append(writer.register_channel(channel.topic, "json", schema_ids[channel.schema_file]))
    writer.add_metadata(RUN_RECORD, encode_run(run_values(episode)))
    writer.add_attachment(create_time=0, log_time=0, name=ROAD_MAP_ATTACHMENT,
                          media_type="application/json",
                          data=log_writer.dumps(road_map_dict(episode.road_map)))
    t0 = log_time_ns(episode.frames[0].scene.t_s)
    writer.add_message(ids[0], t0, log_writer.dumps(MAP_CHANNEL.encode(episode.road_map, t0)), t0)
    for seq, frame in enumerate(episode.frames):
        t_ns = log_time_ns(frame.scene.t_s)
        for cid, channel in zip(ids[1:], FRAME_CHANNELS, strict=True):
            writer.add_message(cid, t_ns, log_writer.dumps(channel.encode(frame, t_ns)), t_ns, seq)
    writer.finish()
    return out.getvalue()


@pytest.mark.parametrize("source", ["synthetic", "simulated"])
def test_the_fast_path_writes_the_plain_paths_bytes(
    source: str, simulated: Episode, monkeypatch: pytest.MonkeyPatch
) -> None:
    episode = simulated if source == "simulated" else synthetic_episode(n_frames=60, seed=3)
    monkeypatch.setattr(log_writer, "ZSTD_LEVEL", 3)  # mcap's Writer cannot choose its level
    monkeypatch.setattr(log_writer, "CHUNK_SIZE_BYTES", 64 * 1024)  # several chunks
    fast = io.BytesIO()
    log_writer.write_stream(episode, fast)
    assert fast.getvalue() == plain_log(episode)


def test_message_objects_serialise_as_their_dicts(simulated: Episode) -> None:
    direct = [c for c in FRAME_CHANNELS if c.message is not None]
    assert {c.topic for c in direct} >= {"/ads/localization", "/ads/prediction/trajectories"}
    for frame in simulated.frames[::25]:
        for channel in direct:
            as_dict = channel.encode(frame, 0)
            assert log_writer.dumps(channel.message(frame)) == log_writer.dumps(as_dict)


def test_the_stacks_arrays_are_contiguous(simulated: Episode) -> None:
    """orjson writes a C-contiguous array itself; any other goes through a Python list."""
    for frame in simulated.frames[::10]:
        for channel in FRAME_CHANNELS:
            if channel.topic in SIM_TOPICS:
                arrays = [v for v in channel.encode(frame, 0).values()
                          if isinstance(v, np.ndarray)]
                assert arrays and all(a.flags.c_contiguous for a in arrays), channel.topic
