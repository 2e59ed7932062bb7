"""Export then import as Apollo records: lossless rates give the native frames back, labels
included; realistic rates lose what the Autoware round trip loses (docs/apollo.md)."""

from __future__ import annotations

import pytest

from evoeye.paths import DataRoot
from evoeye.sources.apollo.export import export_record
from evoeye.sources.apollo.run import RECORDS
from evoeye.sources.autoware.importer import import_bags
from evoeye.store import Warehouse

TOLERANCE = 1e-5


def _rows(root: DataRoot, sql: str) -> list[tuple]:
    table = Warehouse(root).sql(sql)
    return list(zip(*(c.to_pylist() for c in table.columns), strict=True))


@pytest.fixture(scope="module")
def imported(sim_runs, tmp_path_factory) -> dict[str, DataRoot]:
    out = {}
    for rates in ("lossless", "realistic"):
        base = tmp_path_factory.mktemp(f"apollo-{rates}")
        records = [export_record(log, base / "records", rates=rates)
                   for log in sim_runs.logs.values()]
        root = DataRoot.resolve(base / "data")
        report = import_bags(root, records, recordings=RECORDS)
        assert report.failed == [] and len(report.ingest[0].ingested) == 2, report.failed
        out[rates] = root
    return out


def test_lossless_records_give_the_native_features_and_labels(sim_runs, imported,
                                                             same_windows) -> None:
    same_windows(sim_runs.root, imported["lossless"], sorted(sim_runs.logs), TOLERANCE)


def test_lossless_records_keep_the_outcome_and_name_the_label_source(sim_runs,
                                                                     imported) -> None:
    sql = ("SELECT scenario_id, collided, collision_time_s, other_actor, label_source, "
           "software_version FROM scenarios ORDER BY scenario_id")
    for n, b in zip(_rows(sim_runs.root, sql), _rows(imported["lossless"], sql), strict=True):
        assert n[:2] == b[:2] and n[3] == b[3]
        assert n[2] == pytest.approx(b[2], abs=1e-6) if n[2] is not None else b[2] is None
        assert b[4] == "ground_truth_objects:/simulation/ground_truth/obstacles"
        assert b[5] == "apollo"


def test_realistic_records_lose_only_the_last_frame_of_a_run_of_even_length(
        sim_runs, imported) -> None:
    sql = "SELECT scenario_id, list(frame ORDER BY frame) FROM frames GROUP BY ALL"
    native = dict(_rows(sim_runs.root, sql))
    assert dict(_rows(imported["realistic"], sql)) == {
        sid: frames[:-1] if len(frames) % 2 == 0 else frames for sid, frames in native.items()}


def test_importing_again_adds_nothing(imported) -> None:
    root = imported["lossless"]
    records = sorted((root.path.parent / "records").iterdir())
    again = import_bags(root, records, recordings=RECORDS)
    assert again.failed == [] and again.ingest[0].ingested == [] and again.ingest[0].skipped == 2
