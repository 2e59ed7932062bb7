"""`evoeye export apollo` and `evoeye import apollo` from the shell; every bad record gets one
line naming the record, the channel and the problem, and leaves nothing behind."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.errors import ExitCode
from evoeye.paths import DataRoot
from evoeye.sources.apollo.export import record_messages
from evoeye.sources.apollo.protos import vendored
from evoeye.sources.apollo.record import write_record
from evoeye.sources.apollo.run import APOLLO_TOPICS, RUN_CHANNEL, read_record_run
from evoeye.sources.autoware.bag import BagError
from evoeye.sources.autoware.export import RATES
from evoeye.store import Warehouse

T = APOLLO_TOPICS
SECONDS_NS = 1_500_000_000


@pytest.fixture(scope="module")
def short(sim_runs):
    """The first 1.5 s of the safe run's record messages, lossless."""
    _, msgs = record_messages(sim_runs.logs[sim_runs.safe()], RATES["lossless"])
    return [m for m in msgs if m[1] < SECONDS_NS]


def _stamp_back(msgs, channel: str, which: int):
    out, seen = [], 0
    for name, t, msg in msgs:
        if name == channel:
            if seen == which:
                msg = type(msg).FromString(msg.SerializeToString())
                msg.header.timestamp_sec = 0.0001
            seen += 1
        out.append((name, t, msg))
    return out


def _retyped(msgs, channel: str):
    chassis = vendored()["apollo.canbus.Chassis"]
    return [(n, t, chassis(speed_mps=1.0) if n == channel else m) for n, t, m in msgs]


REFUSED = {  # name: (spoiler, channel named, problem named)
    "unknown-type": (lambda m: _retyped(m, T.objects), T.objects,
                     "unknown message type apollo.canbus.Chassis"),
    "missing-channel": (lambda m: [x for x in m if x[0] != T.control], T.control,
                        "missing required channel"),
    "out-of-order": (lambda m: _stamp_back(m, T.trajectory, 10), T.trajectory,
                     "out-of-order stamps"),
    "gap": (lambda m: [x for x in m if not (x[0] == T.control and 0.5e9 < x[1] < 1.2e9)],
            T.control, "gap of 0.55 s before the frame at 1.05 s"),
}


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_a_bad_record_is_refused_with_one_line(short, tmp_path, name) -> None:
    spoil, channel, problem = REFUSED[name]
    record = write_record(tmp_path / f"{name}.record", spoil(short))
    with pytest.raises(BagError) as refused:
        read_record_run(record)
    line = str(refused.value)
    assert "\n" not in line and line.startswith(f"{record}: {channel}: "), line
    assert problem in line, line


def test_an_empty_or_cut_record_is_refused_naming_it(short, tmp_path) -> None:
    empty = write_record(tmp_path / "empty.record", [])
    with pytest.raises(BagError, match=r"empty.record: \(record\): no message in the record"):
        read_record_run(empty)
    cut = write_record(tmp_path / "cut.record", short)
    cut.write_bytes(cut.read_bytes()[: cut.stat().st_size // 2])
    with pytest.raises(BagError, match=r"cut.record: \(record\): truncated"):
        read_record_run(cut)


def test_export_then_import_from_the_shell(sim_runs, short, tmp_path: Path) -> None:
    runner = CliRunner()
    records = tmp_path / "records"
    result = runner.invoke(app, ["export", "apollo", "--out", str(records), "--rates",
                                 "lossless", "--root", str(sim_runs.root.path)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in records.iterdir()) == sorted(f"{s}.record"
                                                               for s in sim_runs.logs)
    broken = write_record(tmp_path / "broken.record",  # not the safe run's identity
                          [m for m in _retyped(short, T.objects) if m[0] != RUN_CHANNEL])
    root = DataRoot.resolve(tmp_path / "data")
    result = runner.invoke(app, ["import", "apollo", str(records), str(broken),
                                 "--root", str(root.path)])
    assert result.exit_code == ExitCode.PARTIAL, result.output
    assert "2 recordings converted, 2 runs ingested" in result.stdout
    refused = [line for line in result.output.splitlines() if line.startswith("refused")]
    assert refused == [f"refused {broken}: {T.objects}: unknown message type "
                       "apollo.canbus.Chassis for objects (known: "
                       "apollo.perception.PerceptionObstacles)"]
    assert sorted(p.stem for p in root.runs.rglob("*.mcap")) == sorted(sim_runs.logs)
    result = runner.invoke(app, ["import", "apollo", str(records), "--root", str(root.path)])
    assert result.exit_code == 0 and "0 runs ingested, 2 already in the warehouse" in \
        result.stdout
    n = Warehouse(root).sql("SELECT count(*) AS n FROM scenarios").column("n")[0].as_py()
    assert n == 2


def test_a_mapping_file_renames_channels_and_sets_the_vehicle(short, tmp_path) -> None:
    from evoeye.sources.apollo.run import apollo_mapping
    from evoeye.sources.autoware.config import MappingError, load_mapping

    toml = tmp_path / "apollo.toml"
    toml.write_text('[topics]\ncontrol = "/apollo/control_v2"\n[vehicle]\nmax_steer_rad = 0.25\n')
    mapping = load_mapping(toml, apollo_mapping())
    assert mapping.topics.control == "/apollo/control_v2"
    assert mapping.topics.odometry == T.odometry and mapping.vehicle.max_steer_rad == 0.25
    renamed = [("/apollo/control_v2" if n == T.control else n, t, m) for n, t, m in short]
    record = write_record(tmp_path / "renamed.record", renamed)
    default, mapped = read_record_run(write_record(tmp_path / "plain.record", short)), \
        read_record_run(record, mapping)
    steer = [f.messages["/ads/control/command"]["steering_rad"] for f in mapped.frames]
    assert steer == pytest.approx([0.5 * f.messages["/ads/control/command"]["steering_rad"]
                                   for f in default.frames])  # half the range, half the angle
    assert max(abs(s) for s in steer) > 1e-4
    toml.write_text('[planning_factors]\n"/x" = "yield"\n')
    with pytest.raises(MappingError, match="not on factor topics"):
        load_mapping(toml, apollo_mapping())
    result = CliRunner().invoke(app, ["import", "apollo", str(record), "--root",
                                      str(tmp_path / "data"), "--mapping", str(toml)])
    assert result.exit_code == ExitCode.USER_ERROR and "not on factor topics" in result.output
