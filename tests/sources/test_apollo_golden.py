"""The golden Apollo record is small, is what the exporter writes, and imports as a run."""

from __future__ import annotations

import importlib.util
import lzma
import sys
from pathlib import Path

from evoeye.sources.apollo.record import read_record
from evoeye.sources.apollo.run import APOLLO_TOPICS, read_record_run

DATA = Path(__file__).resolve().parents[1] / "data" / "apollo"


def _golden_record():
    spec = importlib.util.spec_from_file_location("make_golden_apollo", DATA / "make_golden.py")
    module = sys.modules.setdefault(spec.name, importlib.util.module_from_spec(spec))
    spec.loader.exec_module(module)
    return module


def test_the_golden_record_is_small_and_is_what_the_exporter_writes(tmp_path: Path) -> None:
    kept = (DATA / "golden.record.xz").read_bytes()
    assert len(kept) < 100_000
    again = _golden_record().golden_record(tmp_path)
    assert again.read_bytes() == lzma.decompress(kept)


def test_the_golden_record_has_apollo_s_channels_and_imports_as_its_run(tmp_path) -> None:
    path = tmp_path / "golden.record"
    path.write_bytes(lzma.decompress((DATA / "golden.record.xz").read_bytes()))
    record = read_record(path)
    types = {c.name: c.message_type for c in record.channels.values()}
    assert types[APOLLO_TOPICS.odometry] == "apollo.localization.LocalizationEstimate"
    assert types[APOLLO_TOPICS.trajectory] == "apollo.planning.ADCTrajectory"
    assert types[APOLLO_TOPICS.control] == "apollo.control.ControlCommand"
    run = read_record_run(path)
    assert len(run.frames) == 20 and run.metadata["logical_scenario"] == "highway-cut-in"
    assert run.metadata["label_source"] == \
        f"ground_truth_objects:{APOLLO_TOPICS.ground_truth_objects}"


def test_the_golden_record_decodes_with_apollo_modules_own_descriptors(tmp_path) -> None:
    # the descriptors cyber-record wrote from apollo-modules' classes into the record it made
    # (tests/data/apollo/make_foreign_record.py) decode evoeye's record as the vendored do
    from google.protobuf.unknown_fields import UnknownFieldSet

    from evoeye.sources.apollo.protos import classes_from_proto_desc, vendored

    foreign, golden = tmp_path / "foreign.record", tmp_path / "golden.record"
    foreign.write_bytes(lzma.decompress((DATA / "foreign.record.xz").read_bytes()))
    golden.write_bytes(lzma.decompress((DATA / "golden.record.xz").read_bytes()))
    theirs, ours = read_record(foreign), read_record(golden)
    shared = sorted(set(theirs.channels) & set(ours.channels))
    assert shared == sorted(["/apollo/control", "/apollo/localization/pose", "/apollo/planning",
                             "/apollo/perception/obstacles", "/apollo/prediction"])
    for name in shared:
        kind = theirs.channels[name].message_type
        assert ours.channels[name].message_type == kind
        cls = classes_from_proto_desc(theirs.channels[name].proto_desc)[kind]
        for channel, _, raw in ours.messages:
            if channel == name:
                decoded = cls.FromString(raw)
                assert decoded.ListFields() and not len(UnknownFieldSet(decoded))
                assert decoded.SerializeToString() == \
                    vendored()[kind].FromString(raw).SerializeToString()
