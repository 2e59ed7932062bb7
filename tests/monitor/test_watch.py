"""`evoeye watch` follows a bag as it is written and says what `evoeye replay` says of the same run.

The tiny warehouse's runs are exported as Autoware bags at realistic rates. Watching a bag gives,
frame for frame, the scores and alarms of replaying the run log its import wrote; the follower
reads a file that grows in pieces (a partial record waits) as it reads the whole file.
"""

from __future__ import annotations

from pathlib import Path

import orjson
import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.log.records import UNLABELLED
from evoeye.monitor.protocol import WARNING_K
from evoeye.monitor.registry import load_monitor
from evoeye.monitor.replay import RISK_TOPIC, replay
from evoeye.monitor.runtime import RuntimeMonitor
from evoeye.monitor.watch import Watch
from evoeye.paths import DataRoot
from evoeye.sources.autoware.config import Mapping
from evoeye.sources.autoware.export import export_run
from evoeye.sources.autoware.follow import McapFollower, follow
from evoeye.sources.autoware.frames import FrameAssembler
from evoeye.sources.autoware.importer import import_bags


@pytest.fixture(scope="module")
def bag(tiny, tmp_path_factory) -> Path:
    """A colliding tiny run, as an Autoware bag at realistic rates."""
    sid = tiny.ids["test"][0]
    return export_run(tiny.logs[sid], tmp_path_factory.mktemp("watch"), rates="realistic")


def _watch(tiny, trained, bag: Path, out: Path, lines: list[bytes]) -> list:
    runtime = RuntimeMonitor(load_monitor(tiny.root, trained), consecutive=WARNING_K)
    assembler = FrameAssembler(Mapping(), UNLABELLED)
    watch = Watch(runtime, out, lines.append)
    for topic, msgtype, msg, log_ns in follow(next(bag.glob("*.mcap")), idle_s=0.0):
        for frame in assembler.push(topic, msgtype, msg, log_ns):
            watch.step(frame.messages, frame.t_ns)
    for frame in assembler.finish():
        watch.step(frame.messages, frame.t_ns)
    watch.close()
    return watch.states


def test_watch_alarms_equal_replay_of_the_imported_log(tiny, trained, bag, tmp_path) -> None:
    lines: list[bytes] = []
    states = _watch(tiny, trained, bag, tmp_path / "risk.mcap", lines)
    root = DataRoot.resolve(tmp_path / "data")
    (log,) = import_bags(root, [bag]).logs
    report = replay(log, load_monitor(tiny.root, trained), tmp_path / "replay.mcap")
    with open(report.out, "rb") as f:
        replayed = [orjson.loads(m.data) for _, c, m in make_reader(f).iter_messages()
                    if c.topic == RISK_TOPIC]
    assert len(states) == len(replayed) == report.frames > 30
    assert [s.alarm for s in states] == [r["alarm"] for r in replayed]
    assert any(s.alarm for s in states) and not all(s.alarm for s in states)
    assert [s.score for s in states] == pytest.approx([r["score"] for r in replayed], abs=1e-6)
    assert [orjson.loads(line)["alarm"] for line in lines] == [s.alarm for s in states]
    with open(tmp_path / "risk.mcap", "rb") as f:
        reader = make_reader(f)
        topics = [c.topic for _, c, _ in reader.iter_messages()]
    assert topics.count(RISK_TOPIC) == len(states) and "/monitor/log" in topics


def test_the_follower_reads_a_growing_file_as_the_whole(bag, tmp_path) -> None:
    data = next(bag.glob("*.mcap")).read_bytes()
    whole = McapFollower(next(bag.glob("*.mcap"))).poll()
    growing = tmp_path / "growing.mcap"
    growing.write_bytes(b"")
    follower, got = McapFollower(growing), []
    for end in range(0, len(data) + 997, 997):  # pieces that cut records anywhere
        growing.write_bytes(data[:end])
        got += follower.poll()
    assert follower.finished
    assert [(t, ns) for t, _, _, ns in got] == [(t, ns) for t, _, _, ns in whole]
    assert len(whole) > 100


def test_a_folder_of_split_bags_is_followed_in_order(bag, tmp_path) -> None:
    data = next(bag.glob("*.mcap")).read_bytes()
    split = tmp_path / "split"
    split.mkdir()
    for i in (1, 0):  # the same file twice, as two splits
        (split / f"run_{i}.mcap").write_bytes(data)
    got = list(follow(split, idle_s=0.0))
    single = list(follow(next(bag.glob("*.mcap")), idle_s=0.0))
    assert len(got) == 2 * len(single)


def test_cli_watch_writes_json_lines_and_a_risk_mcap(tiny, trained, bag, tmp_path) -> None:
    out = tmp_path / "cli-risk.mcap"
    result = CliRunner().invoke(app, ["watch", str(bag), "--monitor", trained, "--root",
                                      str(tiny.root.path), "--out", str(out), "--idle-s", "0"])
    assert result.exit_code == 0, result.output
    rows = [orjson.loads(line) for line in result.stdout.splitlines() if line.startswith("{")]
    assert len(rows) > 30 and set(rows[0]) == {"t_s", "score", "alarm", "threshold",
                                               "monitor_version"}
    assert out.stat().st_size > 0
