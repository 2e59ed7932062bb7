"""The exported bags are standard: rosbags and mcap-ros2-support read them with the Autoware type
names and fields; the golden bag is what the exporter writes; old type names and definition-less
`.db3` bags import to the same frames."""

from __future__ import annotations

import dataclasses
import importlib.util
import sqlite3
from pathlib import Path

import numpy as np
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from evoeye.sources.autoware.bag import read_bag
from evoeye.sources.autoware.config import Topics
from evoeye.sources.autoware.typestore import typestore

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "autoware" / "golden"
T = Topics()
TYPES = {
    T.odometry: "nav_msgs/msg/Odometry",
    T.objects: "autoware_perception_msgs/msg/TrackedObjects",
    T.predicted: "autoware_perception_msgs/msg/PredictedObjects",
    T.trajectory: "autoware_planning_msgs/msg/Trajectory",
    T.control: "autoware_control_msgs/msg/Control",
    T.velocity_limit: "autoware_internal_planning_msgs/msg/VelocityLimit",
    T.mrm_state: "autoware_adapi_v1_msgs/msg/MrmState",
    "/planning/planning_factors/obstacle_stop":
        "autoware_internal_planning_msgs/msg/PlanningFactorArray",
}


def _make_golden():
    spec = importlib.util.spec_from_file_location("make_golden", GOLDEN.parent / "make_golden.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.golden_bag


def test_the_golden_bag_is_small_and_is_what_the_exporter_writes(tmp_path: Path) -> None:
    kept = {p.name: p.read_bytes() for p in GOLDEN.iterdir()}
    assert sum(len(b) for b in kept.values()) < 100_000
    again = _make_golden()(tmp_path)
    assert {p.name: p.read_bytes() for p in again.iterdir()} == kept


def test_rosbags_reads_the_bag_with_the_embedded_autoware_types_and_fields() -> None:
    with AnyReader([GOLDEN]) as reader:  # no typestore: the definitions in the bag only
        types = {c.topic: c.msgtype for c in reader.connections}
        assert {t: types[t] for t in TYPES} == TYPES
        seen = {}
        for conn, _, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            if getattr(msg, "objects", True):  # the first message with objects, if a list
                seen.setdefault(conn.topic, msg)
    obj = seen[T.objects].objects[0]
    assert len(obj.object_id.uuid) == 16 and 0.0 <= obj.existence_probability <= 1.0
    assert obj.kinematics.pose_with_covariance.pose.orientation.w != 0.0
    point = seen[T.trajectory].points[1]
    assert point.time_from_start.nanosec == 100_000_000 and point.longitudinal_velocity_mps > 0
    assert seen[T.odometry].child_frame_id == "base_link"
    assert seen[T.control].longitudinal.is_defined_acceleration
    paths = seen[T.predicted].objects[0].kinematics.predicted_paths
    assert paths[0].time_step.nanosec == 100_000_000 and len(paths[0].path) == 31  # t = 0 …3 s


def test_mcap_ros2_support_decodes_every_message() -> None:
    with open(next(GOLDEN.glob("*.mcap")), "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        decoded = list(reader.iter_decoded_messages())
    assert len(decoded) == 280
    by_topic = {c.topic: (s.name, m) for s, c, _, m in decoded}
    assert {t: by_topic[t][0] for t in TYPES} == TYPES
    odometry = by_topic[T.odometry][1]
    assert odometry.header.frame_id == "map" and odometry.twist.twist.linear.x > 0
    factors = by_topic["/planning/planning_factors/obstacle_stop"][1]
    assert isinstance(factors.factors, list) and factors.header.frame_id == "map"
    assert by_topic[T.trajectory][1].points[0].pose.orientation.w != 0.0


def test_the_golden_bag_imports_labelled_by_its_collision_topic() -> None:
    run = read_bag(GOLDEN)
    assert len(run.frames) == 20
    assert run.metadata["label_source"] == f"collision_topic:{T.collision}"
    assert run.metadata["logical_scenario"] == "external"  # no evoeye identity in it



def test_an_exported_bag_keeps_its_run_s_ads_profile_an_older_one_the_default(
        sim_runs, messages, bag_at, tmp_path: Path) -> None:
    meta, msgs = messages(sim_runs.safe())
    msgs = [m for m in msgs if m[0] < 500_000_000]
    cautious = read_bag(bag_at(tmp_path / "cautious", msgs, {**meta, "ads_profile": "cautious"}))
    assert cautious.metadata["ads_profile"] == "cautious"
    before_profiles = {k: v for k, v in meta.items() if k != "ads_profile"}
    assert read_bag(bag_at(tmp_path / "old", msgs, before_profiles)).metadata[
        "ads_profile"] == "default"
    assert read_bag(bag_at(tmp_path / "foreign", msgs)).metadata["ads_profile"] == "default"

# -- old type names (autoware_auto_*, before 2024): their own definitions, the same frames -------
OLD = {  # old type → its definition; the fields a converter reads have the same names
    "autoware_auto_perception_msgs/msg/TrackedObjectKinematics":
        "geometry_msgs/PoseWithCovariance pose_with_covariance\nuint8 orientation_availability\n"
        "geometry_msgs/TwistWithCovariance twist_with_covariance\n"
        "geometry_msgs/AccelWithCovariance acceleration_with_covariance\nbool is_stationary\n",
    "autoware_auto_control_msgs/msg/AckermannLateralCommand":
        "builtin_interfaces/Time stamp\nfloat32 steering_tire_angle\n"
        "float32 steering_tire_rotation_rate\n",
    "autoware_auto_control_msgs/msg/LongitudinalCommand":
        "builtin_interfaces/Time stamp\nfloat32 speed\nfloat32 acceleration\nfloat32 jerk\n",
    "autoware_auto_control_msgs/msg/AckermannControlCommand":
        "builtin_interfaces/Time stamp\n"
        "autoware_auto_control_msgs/AckermannLateralCommand lateral\n"
        "autoware_auto_control_msgs/LongitudinalCommand longitudinal\n",
}
RENAMED = {"autoware_perception_msgs": "autoware_auto_perception_msgs",
           "autoware_planning_msgs": "autoware_auto_planning_msgs"}


def _old_store():
    from rosbags.typesys import get_types_from_msg

    store = typestore()
    types = {}
    for name, path in sorted(_vendored().items()):
        pkg = name.split("/")[0]
        if pkg in RENAMED:
            text = path.read_text()
            for new, old in RENAMED.items():
                text = text.replace(f"{new}/", f"{old}/")
            types.update(get_types_from_msg(text, name.replace(pkg, RENAMED[pkg])))
    for name, text in OLD.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def _vendored():
    from evoeye.sources.autoware.typestore import msg_files

    return msg_files()


def _retyped(msg, store, name: str):
    """`msg` rebuilt as the old type `name`, field by field (speed ← velocity)."""
    cls = store.types[name]
    values = {}
    for f in dataclasses.fields(cls):
        if f.name == "__msgtype__":
            continue
        value = getattr(msg, "velocity" if f.name == "speed" else f.name)
        values[f.name] = _convert(value, store)
    return cls(**values)


def _convert(value, store):
    if isinstance(value, list):
        return [_convert(v, store) for v in value]
    kind = getattr(value, "__msgtype__", "")
    old = {"autoware_perception_msgs/msg/TrackedObjectKinematics":
           "autoware_auto_perception_msgs/msg/TrackedObjectKinematics",
           "autoware_control_msgs/msg/Lateral":
           "autoware_auto_control_msgs/msg/AckermannLateralCommand",
           "autoware_control_msgs/msg/Longitudinal":
           "autoware_auto_control_msgs/msg/LongitudinalCommand"}.get(kind)
    pkg = kind.split("/")[0]
    if old is None and pkg in RENAMED:
        old = kind.replace(pkg, RENAMED[pkg])
    return _retyped(value, store, old) if old else value


def test_old_autoware_auto_type_names_import_to_the_same_frames(sim_runs, messages,
                                                                tmp_path: Path) -> None:
    from evoeye.sources.autoware.export import write_bag

    _, msgs = messages(sim_runs.safe())
    msgs = [m for m in msgs if m[0] < 1_000_000_000]
    store = _old_store()
    old = []
    for t, topic, kind, msg in msgs:
        if kind == "autoware_control_msgs/msg/Control":
            kind = "autoware_auto_control_msgs/msg/AckermannControlCommand"
            msg = _retyped(msg, store, kind)
        elif kind.split("/")[0] in RENAMED:
            pkg = kind.split("/")[0]
            kind = kind.replace(pkg, RENAMED[pkg])
            msg = _retyped(msg, store, kind)
        old.append((t, topic, kind, msg))
    new_run = read_bag(write_bag(tmp_path / "new", msgs))
    old_bag = write_bag(tmp_path / "old", old, store=store)
    with AnyReader([old_bag]) as reader:
        assert {c.msgtype for c in reader.connections} >= {
            "autoware_auto_perception_msgs/msg/TrackedObjects",
            "autoware_auto_control_msgs/msg/AckermannControlCommand"}
    old_run = read_bag(old_bag)
    assert [f.messages for f in old_run.frames] == [f.messages for f in new_run.frames]


def test_a_db3_bag_without_definitions_imports_with_the_vendored_types(sim_runs, messages,
                                                                       tmp_path: Path) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer

    _, msgs = messages(sim_runs.safe())
    msgs = [m for m in msgs if m[0] < 1_000_000_000]
    store = typestore()
    bag = tmp_path / "humble"
    with Writer(bag, version=8, storage_plugin=StoragePlugin.SQLITE3) as writer:
        conns = {}
        for t, topic, kind, msg in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, kind, typestore=store)
            writer.write(conns[topic], t, store.serialize_cdr(msg, kind))
    db3 = next(bag.glob("*.db3"))
    with sqlite3.connect(db3) as con:  # as Humble writes it: no message definitions
        con.execute("DELETE FROM message_definitions")
    from evoeye.sources.autoware.export import write_bag

    mcap_run = read_bag(write_bag(tmp_path / "mcap", msgs))
    db3_run = read_bag(bag)
    assert len(db3_run.frames) == 20
    a = np.array([f.messages["/ads/localization"]["x_m"] for f in db3_run.frames])
    b = np.array([f.messages["/ads/localization"]["x_m"] for f in mcap_run.frames])
    assert np.array_equal(a, b)
