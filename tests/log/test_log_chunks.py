"""Reading a few topics walks the chunks directly: the same messages as `mcap`'s reader."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from evoeye.log import read_run
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
