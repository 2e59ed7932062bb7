"""Reading a few topics walks the chunks directly: same messages as `mcap`'s reader, same errors."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from evoeye.log import LogError, read_run
from evoeye.log.channels import TOPICS


def _reference(path: Path, topics: list[str]) -> dict[str, list[tuple[int, bytes]]]:
    out: dict[str, list[tuple[int, bytes]]] = {}
    with path.open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(topics=topics):
            out.setdefault(channel.topic, []).append((message.log_time, message.data))
    return out


@pytest.mark.parametrize("topics", [[TOPICS.ground_truth], [TOPICS.control, TOPICS.obstacles],
                                    list(TOPICS)])
def test_topic_reads_equal_the_mcap_reader(log_path: Path, topics: list[str]) -> None:
    run = read_run(log_path, topics=topics)
    assert run.raw == _reference(log_path, topics)
    assert run.raw == {t: read_run(log_path).raw[t] for t in run.raw}


def test_a_topic_the_file_lacks_reads_empty(log_path: Path) -> None:
    run = read_run(log_path, topics=["/not/there"])
    assert run.raw == {} and run.messages("/not/there") == []


def test_a_corrupt_chunk_is_a_log_error_on_a_topic_read(log_path: Path, tmp_path: Path) -> None:
    data = bytearray(log_path.read_bytes())
    middle = len(data) // 3
    data[middle : middle + 64] = bytes(64)  # inside the first chunk's compressed data
    bad = tmp_path / "corrupt.mcap"
    bad.write_bytes(bytes(data))
    with pytest.raises(LogError, match="corrupt") as info:
        read_run(bad, topics=[TOPICS.ground_truth])
    assert str(bad) in str(info.value)
