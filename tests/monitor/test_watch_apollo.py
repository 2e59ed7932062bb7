"""`evoeye watch` on an Apollo cyber record: a record read as it grows gives what the whole
record gives, and watching it says what `evoeye replay` says of the log its import wrote."""

from __future__ import annotations

import orjson
import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.monitor.registry import load_monitor
from evoeye.monitor.replay import RISK_TOPIC, replay
from evoeye.paths import DataRoot
from evoeye.sources.apollo.export import export_record
from evoeye.sources.apollo.follow import RecordFollower, is_record, record_splits
from evoeye.sources.apollo.record import read_record
from evoeye.sources.apollo.run import RECORDS
from evoeye.sources.autoware.importer import import_bags


@pytest.fixture(scope="module")
def record(tiny, tmp_path_factory):
    """A colliding tiny run, as an Apollo record at realistic rates."""
    sid = tiny.ids["test"][0]
    return export_record(tiny.logs[sid], tmp_path_factory.mktemp("apollo"), rates="realistic")


def test_a_growing_record_is_read_as_the_whole(record, tmp_path) -> None:
    data = record.read_bytes()
    growing = tmp_path / "growing.record"
    growing.write_bytes(b"")
    follower, got = RecordFollower(growing), []
    for end in range(0, len(data) + 4999, 4999):  # pieces that cut sections anywhere
        growing.write_bytes(data[:end])
        got += follower.poll()
    assert follower.finished
    whole = read_record(record)
    assert [(c, t) for c, _, _, t in got] == [(c, t) for c, t, _ in whole.messages]
    assert [m.SerializeToString() for _, _, m, _ in got] == [raw for _, _, raw in whole.messages]


def test_split_records_are_followed_in_order(tmp_path) -> None:
    for name in ("run.record.00010", "run.record.00002", "notes.txt"):
        (tmp_path / name).write_bytes(b"")
    assert [p.name for p in record_splits(tmp_path)] == ["run.record.00002", "run.record.00010"]
    assert is_record(tmp_path) and is_record(tmp_path / "x.record")
    assert not is_record(tmp_path / "x.mcap")


def test_cli_watch_on_a_record_alarms_as_replay_of_its_import(tiny, trained, record,
                                                              tmp_path) -> None:
    out = tmp_path / "risk.mcap"
    result = CliRunner().invoke(app, ["watch", str(record), "--monitor", trained, "--root",
                                      str(tiny.root.path), "--out", str(out), "--idle-s", "0"])
    assert result.exit_code == 0, result.output
    rows = [orjson.loads(line) for line in result.stdout.splitlines() if line.startswith("{")]
    root = DataRoot.resolve(tmp_path / "data")
    (log,) = import_bags(root, [record], recordings=RECORDS).logs
    report = replay(log, load_monitor(tiny.root, trained), tmp_path / "replay.mcap")
    with open(report.out, "rb") as f:
        replayed = [orjson.loads(m.data) for _, c, m in make_reader(f).iter_messages()
                    if c.topic == RISK_TOPIC]
    assert len(rows) == len(replayed) == report.frames > 30
    assert [r["alarm"] for r in rows] == [r["alarm"] for r in replayed]
    assert any(r["alarm"] for r in rows) and not all(r["alarm"] for r in rows)
    assert [r["score"] for r in rows] == pytest.approx([r["score"] for r in replayed], abs=1e-6)
