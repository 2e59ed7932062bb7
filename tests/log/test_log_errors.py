"""Bad logs raise LogError naming the file; a failed write leaves nothing behind."""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import numpy as np
import pytest

from evoeye.log import LogError, read_run, write_episode
from evoeye.log.channels import TOPICS
from evoeye.log.mcap_writer import McapWriter
from evoeye.sim.episode import Episode, Frame


def expect_log_error(path: Path, match: str, topics: list[str] | None = None) -> None:
    with pytest.raises(LogError, match=match) as info:
        read_run(path, topics=topics)
    assert str(path) in str(info.value)


def test_truncated_copy(log_path: Path, tmp_path: Path) -> None:
    data = log_path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    expect_log_error(cut, "truncated")


def test_random_bytes(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(np.random.default_rng(0).bytes(4096))
    expect_log_error(junk, "not an MCAP file")


def test_empty_file(tmp_path: Path) -> None:
    empty = tmp_path / "empty.mcap"
    empty.touch()
    expect_log_error(empty, "empty")


def test_missing_file(tmp_path: Path) -> None:
    expect_log_error(tmp_path / "absent.mcap", "cannot read")


@pytest.mark.parametrize("topics", [None, [TOPICS.ground_truth]])  # mcap's reader; chunks.py
def test_corrupt_chunk(log_path: Path, tmp_path: Path, topics: list[str] | None) -> None:
    data = bytearray(log_path.read_bytes())
    middle = len(data) // 3
    data[middle : middle + 64] = bytes(64)  # inside the first chunk's compressed data
    bad = tmp_path / "corrupt.mcap"
    bad.write_bytes(bytes(data))
    expect_log_error(bad, "corrupt", topics)


def test_file_without_run_record(tmp_path: Path) -> None:
    buf = io.BytesIO()
    writer = McapWriter(buf)
    writer.start(library="test")
    schema = writer.register_schema("x", "jsonschema", b"{}")
    channel = writer.register_channel("/x", "json", schema)
    writer.add_message(channel, 0, b"{}", 0)
    writer.finish()
    path = tmp_path / "norecord.mcap"
    path.write_bytes(buf.getvalue())
    expect_log_error(path, "no 'evoeye.run' metadata record")


def test_invalid_run_record(tmp_path: Path) -> None:
    buf = io.BytesIO()
    writer = McapWriter(buf)
    writer.start(library="test")
    writer.add_metadata("evoeye.run", {"seed": "not json"})
    writer.finish()
    path = tmp_path / "badrecord.mcap"
    path.write_bytes(buf.getvalue())
    expect_log_error(path, "invalid 'evoeye.run' record")


def _with_bad_frame(episode: Episode) -> Episode:
    """The episode with an unserialisable value in its last frame."""
    last = episode.frames[-1]
    obstacles = dataclasses.replace(last.messages.obstacles, obj_class=[object()])
    messages = dataclasses.replace(last.messages, obstacles=obstacles)
    frames = [*episode.frames[:-1], Frame(last.scene, messages)]
    return dataclasses.replace(episode, frames=frames)


def test_failed_write_leaves_no_file(episode: Episode, tmp_path: Path) -> None:
    with pytest.raises(TypeError):
        write_episode(_with_bad_frame(episode), tmp_path / "run.mcap")
    assert list(tmp_path.iterdir()) == []


def test_failed_rewrite_keeps_the_old_log(episode: Episode, tmp_path: Path) -> None:
    path = write_episode(episode, tmp_path / "run.mcap")
    before = path.read_bytes()
    with pytest.raises(TypeError):
        write_episode(_with_bad_frame(episode), path)
    assert path.read_bytes() == before
    assert list(tmp_path.iterdir()) == [path]


def test_interrupt_mid_write_leaves_no_file(
    episode: Episode, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def interrupted(self: McapWriter) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(McapWriter, "finish", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_episode(episode, tmp_path / "run.mcap")
    assert list(tmp_path.iterdir()) == []


def test_partial_temp_file_is_not_a_log(episode: Episode, tmp_path: Path) -> None:
    """What a killed writer leaves (a prefix of the bytes) is refused as truncated."""
    data = write_episode(episode, tmp_path / "run.mcap").read_bytes()
    partial = tmp_path / "run.mcap.123.tmp"
    partial.write_bytes(data[: len(data) - 100])
    expect_log_error(partial, "truncated")
