"""The ingest flow end to end through Prefect: logs on disk → warehouse, re-run adds nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_episode
from evoeye.paths import DataRoot
from evoeye.store import Warehouse
from flows.ingest import IngestParams, ingest_flow


@pytest.fixture
def root_with_logs(tmp_path: Path) -> DataRoot:
    root = DataRoot.resolve(tmp_path / "data")
    for seed in range(2):
        ep = synthetic_episode(n_frames=10, seed=seed)
        path = root.run_log(ep.spec.scenario, ep.spec.batch, ep.spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_episode(ep, path)
    bad = root.run_log("highway-cut-in", "b000", "broken")
    bad.write_bytes(b"not an mcap file")
    return root


def test_ingest_flow_ingests_quarantines_and_is_idempotent(
    prefect_server: None, root_with_logs: DataRoot, latest_artifact, flow_run_names
) -> None:
    params = IngestParams(root=str(root_with_logs.path), runs_per_part=1)
    report = ingest_flow(params)
    assert len(report["ingested"]) == 2 and report["frames"] == 20
    assert [log for log, _ in report["quarantined"]] == ["runs/highway-cut-in/b000/broken.mcap"]
    counts = Warehouse(root_with_logs).sql(
        "SELECT count(*) AS runs, sum(n_frames) AS frames FROM scenarios"
    ).to_pylist()[0]
    assert counts == {"runs": 2, "frames": 20}

    md = latest_artifact("evoeye-ingest")
    assert "| 2 | 20 | 0 | 1 |" in md and "quarantined `runs/highway-cut-in/b000/broken.mcap`" in md
    assert flow_run_names(f"ingest-{root_with_logs.path.name}")

    again = ingest_flow(params)
    assert again["ingested"] == [] and again["skipped"] == 2 and again["quarantined"] == []
