"""Apollo's cyber records without Apollo: a record cyber-record wrote from apollo-modules' protos
(tests/data/apollo/make_foreign_record.py) reads, with its own descriptors and the vendored
ones alike; evoeye's writer gives a record its reader reads back; bad files are one line."""

from __future__ import annotations

import lzma
import math
from collections import Counter
from pathlib import Path

import pytest
from google.protobuf import __version__ as protobuf_version

from evoeye.sources.apollo.protos import classes_from_proto_desc, vendored
from evoeye.sources.apollo.record import (
    HEADER_LENGTH,
    INDEX,
    SECTION,
    RecordError,
    read_record,
    write_record,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "apollo"
LOCALIZATION = "/apollo/localization/pose"


def _load(name: str):
    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location(name, DATA / f"{name}.py")
    module = sys.modules.setdefault(name, importlib.util.module_from_spec(spec))
    spec.loader.exec_module(module)
    return module


foreign_spec = _load("make_foreign_record")


@pytest.fixture(scope="module")
def foreign(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("apollo") / "foreign.record"
    path.write_bytes(lzma.decompress((DATA / "foreign.record.xz").read_bytes()))
    return path


def test_the_vendored_descriptors_build_the_six_message_types_on_this_protobuf() -> None:
    assert int(protobuf_version.split(".")[0]) >= 7  # beside evoeye's protobuf, not 3.20
    types = vendored()
    for name in ("apollo.localization.LocalizationEstimate", "apollo.canbus.Chassis",
                 "apollo.perception.PerceptionObstacles", "apollo.prediction.PredictionObstacles",
                 "apollo.planning.ADCTrajectory", "apollo.control.ControlCommand"):
        assert name in types
    msg = types["apollo.planning.ADCTrajectory"](total_path_length=3.5)
    assert types["apollo.planning.ADCTrajectory"].FromString(msg.SerializeToString()) == msg


def test_a_record_written_by_cyber_record_reads_channels_rates_and_values(foreign) -> None:
    record = read_record(foreign)
    assert record.header.is_complete and record.header.message_number == 165
    counts = Counter(c for c, _, _ in record.messages)
    assert counts == {c: foreign_spec.DURATION_NS // p for c, p in foreign_spec.CHANNELS.items()}
    channel = record.channels[LOCALIZATION]
    assert channel.message_type == "apollo.localization.LocalizationEstimate"
    own = classes_from_proto_desc(channel.proto_desc)[channel.message_type]
    ours = vendored()[channel.message_type]
    for name, t_ns, raw in record.messages:
        if name != LOCALIZATION:
            continue
        a, b = own.FromString(raw), ours.FromString(raw)
        assert a.SerializeToString() == b.SerializeToString()  # the same fields either way
        want = foreign_spec.expected((t_ns - foreign_spec.T0_NS) / 1e9)
        assert (b.pose.position.x, b.pose.position.y) == pytest.approx((want["x"], want["y"]))
        assert b.header.timestamp_sec == pytest.approx(t_ns / 1e9)


def test_evoeye_s_writer_gives_a_record_its_reader_reads_back(foreign, tmp_path) -> None:
    record = read_record(foreign)
    msgs = [(c, t, vendored()[record.channels[c].message_type].FromString(raw))
            for c, t, raw in record.messages]
    out = write_record(tmp_path / "ours.record", msgs, chunk_messages=64)
    back = read_record(out)
    assert back.messages == record.messages
    assert {c.name: c.message_type for c in back.channels.values()} == \
        {c.name: c.message_type for c in record.channels.values()}
    assert back.header.is_complete and back.header.chunk_number == 3  # 165 = 64 + 64 + 37
    data = out.read_bytes()
    kind, _ = SECTION.unpack_from(data, back.header.index_position)
    assert kind == INDEX and back.header.size == len(data)
    assert not list(tmp_path.glob(".*partial"))


@pytest.mark.parametrize(("spoil", "problem"), [
    (lambda b: b"", "empty file"),
    (lambda b: b[: len(b) // 2], "truncated"),
    (lambda b: b[: HEADER_LENGTH + SECTION.size + 5], "truncated"),
    (lambda b: SECTION.pack(4, 3) + b"abc" + bytes(HEADER_LENGTH), "not a cyber record"),
])
def test_a_bad_record_is_one_line_naming_the_problem(foreign, tmp_path, spoil, problem) -> None:
    bad = tmp_path / "bad.record"
    bad.write_bytes(spoil(foreign.read_bytes()))
    with pytest.raises(RecordError) as refused:
        read_record(bad)
    assert problem in str(refused.value) and "\n" not in str(refused.value)


def test_a_record_cyber_record_wrote_imports_as_an_unlabelled_external_run(foreign) -> None:
    from evoeye.log import TOPICS
    from evoeye.sources.apollo.run import read_record_run

    run = read_record_run(foreign)
    assert run.metadata["logical_scenario"] == "external"
    assert run.metadata["scenario_id"].startswith("apollo_")
    assert run.metadata["label_source"] == "none" and "imported unlabelled" in run.notes[0]
    assert len(run.frames) == 10  # 20 Hz over the half second, from the first pose
    for f in run.frames:
        t = f.t_ns - foreign_spec.T0_NS
        want = foreign_spec.expected(t / 1e9)
        loc, obs = f.messages[TOPICS.localization], f.messages[TOPICS.obstacles]
        # the body centre 1.5 m ahead of the rear axle, re-origined by whole kilometres
        ahead = 1.5 * math.cos(foreign_spec.HEADING), 1.5 * math.sin(foreign_spec.HEADING)
        assert loc["x_m"] == pytest.approx(want["x"] + ahead[0] - 587_000.0)
        assert loc["y_m"] == pytest.approx(want["y"] + ahead[1] - 4_141_000.0)
        assert loc["speed_mps"] == pytest.approx(foreign_spec.SPEED)
        assert obs["track_id"] == [foreign_spec.OBSTACLE_ID] and obs["obj_class"] == ["car"]
        assert obs["x_m"][0] == pytest.approx(want["obs_x"] - 587_000.0)
        assert f.messages[TOPICS.control]["accel_cmd_mps2"] == pytest.approx(0.2)


def test_an_obstacle_given_as_a_polygon_gets_the_box_around_it() -> None:
    from evoeye.sources.apollo.convert import obstacles
    from evoeye.sources.autoware.convert import Context

    msg = vendored()["apollo.perception.PerceptionObstacles"]()
    o = msg.perception_obstacle.add(id=0, theta=math.pi / 2, type=3)  # no length, width
    for x, y in ((9.0, 18.0), (11.0, 18.0), (11.0, 22.0), (9.0, 22.0)):
        o.polygon_point.add(x=x, y=y)
    got = obstacles(msg, Context())
    assert got["track_id"] == [2**31]  # Apollo's id 0 is not evoeye's ego
    assert (got["x_m"][0], got["y_m"][0]) == pytest.approx((10.0, 20.0))
    assert (got["length_m"][0], got["width_m"][0]) == pytest.approx((4.0, 2.0))
    assert (got["vx_mps"], got["obj_class"]) == ([0.0], ["pedestrian"])  # no velocity: at rest
