"""Recordings evoeye did not write: upstream definitions, random UUIDs, real rates, stamps ahead of
bag time, and a Humble `.db3` without definitions (tests/data/autoware/upstream_bag.py)."""

from __future__ import annotations

import dataclasses
import importlib.util
import sqlite3
import sys
from pathlib import Path

import pytest

from evoeye.log import TOPICS
from evoeye.log.records import UNLABELLED
from evoeye.paths import DataRoot
from evoeye.sources.autoware.bag import BagError, read_bag
from evoeye.sources.autoware.config import Mapping
from evoeye.sources.autoware.convert import TrackIds
from evoeye.sources.autoware.follow import follow
from evoeye.sources.autoware.frames import FrameAssembler
from evoeye.sources.autoware.importer import import_bags
from evoeye.store import Warehouse

HERE = Path(__file__).resolve().parents[1] / "data" / "autoware" / "upstream_bag.py"
_spec = importlib.util.spec_from_file_location("upstream_bag", HERE)
up = sys.modules.setdefault("upstream_bag", importlib.util.module_from_spec(_spec))
_spec.loader.exec_module(up)
GT = TOPICS.ground_truth


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> dict[str, Path]:
    drive, store = up.Drive(seed=1), up.upstream_store()
    msgs = drive.messages(store)
    base = tmp_path_factory.mktemp("upstream")
    return {"drive": drive, "msgs": msgs, "store": store,
            "mcap": up.write_mcap(base / "run_mcap", msgs, store),
            "db3": up.write_humble_db3(base / "run_db3", msgs, store)}


def _frame_ns(run) -> list[int]:
    return [f.t_ns for f in run.frames]


def test_a_collision_with_a_random_uuid_imports_with_the_right_label(recorded) -> None:
    drive = recorded["drive"]
    run = read_bag(recorded["mcap"])
    meta = run.metadata
    assert meta["label_source"] == "ground_truth_objects:/simulation/ground_truth/objects"
    contact_ns = up.T0_NS + round(drive.contact_s * 1e9)
    hit = [f for f in run.frames if f.messages[GT]["ego_collision"]]
    first = hit[0]
    # the first frame whose odometry (50 Hz, held) has the ego at the stopped car
    assert contact_ns <= first.t_ns < contact_ns + 50_000_000 + 20_000_000
    assert hit == run.frames[first.index:]  # from then on, never before
    lead = TrackIds()(store_uuid(recorded["store"], drive.uuids[0]))
    assert lead >= 2**31  # beyond the INTEGER columns of layout 4
    assert meta["collided"] and meta["other_actor"] == lead
    assert lead in first.messages[TOPICS.obstacles]["track_id"]
    assert meta["collision_time_s"] == first.messages[GT]["t_s"]


def store_uuid(store, raw: bytes):
    import numpy as np

    return store.types["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(raw, np.uint8).copy())


def test_real_rates_and_stamps_ahead_of_bag_time_give_the_20_hz_frames(recorded) -> None:
    run = read_bag(recorded["mcap"])
    ns = _frame_ns(run)
    assert {b - a for a, b in zip(ns, ns[1:], strict=False)} == {50_000_000}
    assert ns[0] == up.T0_NS + 103_000_000  # the first odometry stamp + 2 periods: by then
    # every required topic has a message (trajectory at +52 ms)
    ages = [f.messages["/ads/message_ages"] for f in run.frames]
    assert max(a["localization_s"] for a in ages) < 0.02 + 1e-9  # by header stamps, not bag
    assert max(a["control_s"] for a in ages) < 1 / 30  # the command in force
    # frames at +3 ms + 50 k ms, trajectories stamped at +52 ms + 100 j ms but received 60 ms
    # later: the one stamped 1 ms before a frame has not arrived when the frame closes (the
    # next odometry, 2 ms late), so a frame holds a trajectory 51 or 101 ms old
    assert {round(a["plan_s"], 6) for a in ages} == {0.051, 0.101}


def test_a_humble_db3_without_definitions_is_the_same_run(recorded) -> None:
    db3 = next(recorded["db3"].glob("*.db3"))
    with sqlite3.connect(db3) as con:
        assert con.execute("SELECT schema_version FROM schema").fetchone() == (3,)
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master")}
    assert "message_definitions" not in tables
    a, b = read_bag(recorded["mcap"]), read_bag(recorded["db3"])
    assert b.metadata == a.metadata  # the run id from the content, not the storage
    assert [f.messages for f in b.frames] == [f.messages for f in a.frames]


def test_the_mcap_and_db3_of_one_recording_import_as_one_run(recorded, tmp_path) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    report = import_bags(root, [recorded["mcap"], recorded["db3"]])
    assert report.failed == [] and len(report.labels) == 1
    again = import_bags(root, [recorded["db3"]])
    assert again.labels == {} and again.ingest[0].skipped == 1
    rows = Warehouse(root).sql(
        "SELECT s.other_actor, max(f.gt_collision_actor) AS actor FROM scenarios s "
        "JOIN frames f USING (scenario_id) GROUP BY ALL").to_pylist()
    lead = read_bag(recorded["mcap"]).metadata["other_actor"]
    assert rows == [{"other_actor": lead, "actor": lead}]


def _watched(path: Path) -> list:
    assembler = FrameAssembler(Mapping(), UNLABELLED)
    frames = []
    for topic, msgtype, msg, log_ns in follow(path, topics=set(assembler.roles), idle_s=0.0):
        frames.extend(assembler.push(topic, msgtype, msg, log_ns))
    frames.extend(assembler.finish())
    return frames


def _unlabelled(frames) -> list:
    return [{k: v for k, v in f.messages.items() if k != GT} for f in frames]


def test_watch_reads_what_import_reads(recorded) -> None:
    imported = read_bag(recorded["mcap"])
    watched = _watched(next(recorded["mcap"].glob("*.mcap")))
    assert [f.t_ns for f in watched] == _frame_ns(imported)
    assert _unlabelled(watched) == _unlabelled(imported.frames)


OLD_CONTROL = {  # a Control of another definition than the vendored one: no control_time
    "autoware_control_msgs/msg/Lateral":
        "builtin_interfaces/Time stamp\nfloat32 steering_tire_angle\n"
        "float32 steering_tire_rotation_rate\nbool is_defined_steering_tire_rotation_rate\n",
    "autoware_control_msgs/msg/Longitudinal":
        "builtin_interfaces/Time stamp\nfloat32 velocity\nfloat32 acceleration\nfloat32 jerk\n"
        "bool is_defined_acceleration\nbool is_defined_jerk\n",
    "autoware_control_msgs/msg/Control":
        "builtin_interfaces/Time stamp\nautoware_control_msgs/Lateral lateral\n"
        "autoware_control_msgs/Longitudinal longitudinal\n",
}


def _old_store():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for path in sorted(up.UPSTREAM.glob("*/msg/*.msg")):
        name = f"{path.parts[-3]}/msg/{path.stem}"
        if name not in OLD_CONTROL:
            types.update(get_types_from_msg(path.read_text(), name))
    for name, text in OLD_CONTROL.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def _without_control_time(msg, store):
    kind = getattr(msg, "__msgtype__", "")
    if kind not in OLD_CONTROL:
        return msg
    cls = store.types[kind]
    return cls(**{f.name: _without_control_time(getattr(msg, f.name), store)
                  for f in dataclasses.fields(cls) if f.name != "__msgtype__"})


def test_a_bag_s_own_definitions_decode_it_in_import_and_watch(recorded, tmp_path) -> None:
    store = _old_store()
    msgs = [(ns, topic, kind, _without_control_time(m, store))
            for ns, topic, kind, m in recorded["msgs"]]
    bag = up.write_mcap(tmp_path / "own", msgs, store)
    imported = read_bag(bag)  # the vendored Control (with control_time) would not decode it
    watched = _watched(next(bag.glob("*.mcap")))
    assert _unlabelled(watched) == _unlabelled(imported.frames)
    assert _unlabelled(imported.frames) == _unlabelled(read_bag(recorded["mcap"]).frames)


def _bag_with_topics(dest: Path, msgs, store) -> Path:
    """An MCAP bag with a connection for every topic of the drive, and `msgs`."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    with Writer(dest, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {topic: writer.add_connection(topic, msgtype, typestore=store)
                 for topic, msgtype, *_ in up.TOPICS.values()}
        for ns, topic, msgtype, msg in msgs:
            writer.write(conns[topic], ns, store.serialize_cdr(msg, msgtype))
    return dest


def test_a_bag_with_topics_but_no_message_says_so(recorded, tmp_path) -> None:
    store = recorded["store"]
    with pytest.raises(BagError, match=r"empty: \(bag\): no message in the bag \(its 6 topics"):
        read_bag(_bag_with_topics(tmp_path / "empty", [], store))
    control = up.TOPICS["control"][0]
    silent = _bag_with_topics(tmp_path / "silent",
                              [m for m in recorded["msgs"] if m[1] != control], store)
    with pytest.raises(BagError) as refused:
        read_bag(silent)
    assert str(refused.value) == (f"{silent}: {control}: no message on a required topic "
                                  "(control)")
