"""The results flow through Prefect: RQ1 of a tiny synthetic root, its files and the artifact."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from pydantic import ValidationError

from evoeye.log.synthetic import SCENARIO, write_synthetic_batch
from evoeye.paths import DataRoot
from evoeye.store import ingest
from flows.results import ResultsParams, results_flow


@pytest.fixture
def root(tmp_path: Path) -> DataRoot:
    root = DataRoot.resolve(tmp_path / "data")
    write_synthetic_batch(root, "init", 12)
    write_synthetic_batch(root, "held", 6, first_seed=100)
    ingest(root)
    return root


def test_the_results_flow_runs_a_part_per_task_and_writes_the_tables(prefect_server: None,
                                                                      root: DataRoot) -> None:
    from prefect.client.orchestration import get_client

    params = ResultsParams(root=str(root.path), scenarios=[SCENARIO], parts=["rq1"],
                           training_seeds=2, test_runs=0, test_batch="held", epochs=1,
                           patience=1, baselines=["ttc", "context-only"], report_name="flow")
    out = results_flow(params)
    folder = Path(out["report_dir"])
    assert folder == root.path / "reports" / "flow"
    results = json.loads((folder / "results.json").read_text())
    assert [t["id"] for t in results["tables"]] == ["rq1"]
    assert [r["method"] for r in results["tables"][0]["rows"]] == ["FusionMonitor", "ttc",
                                                                  "context-only"]
    assert results["scenarios"][SCENARIO]["data"]["splits"]["test"]["scenarios"] == 6
    assert dict(out["findings"])["rq1-baselines"] == results["findings"][0]["verdict"]
    with get_client(sync_client=True) as client:
        artifacts = client.read_artifacts()
    (artifact,) = [a for a in artifacts if a.key == "evoeye-results"]
    assert "FusionMonitor − ttc" in artifact.data


def test_bad_parameters_are_refused_before_anything_runs() -> None:
    with pytest.raises((ValueError, ValidationError), match="unknown baseline"):
        ResultsParams(baselines=["ttc", "radar"], test_runs=0)
    with pytest.raises(ValidationError):
        ResultsParams(training_seeds=1)
    with pytest.raises((ValueError, ValidationError), match="initial runs must be >= 0"):
        ResultsParams(initial_runs={"highway-cut-in": -1, "unprotected-intersection": 5})


def test_initial_runs_per_scenario_reach_the_config() -> None:
    from evoeye.results.config import PAPER_INITIAL_RUNS

    paper = ResultsParams(scenarios=list(PAPER_INITIAL_RUNS), initial_runs=PAPER_INITIAL_RUNS)
    assert paper.config().initial_runs == PAPER_INITIAL_RUNS
    with pytest.raises(ValueError, match="give every scenario initial runs"):
        ResultsParams(initial_runs=PAPER_INITIAL_RUNS)  # every registered one: S3 has none
    assert ResultsParams(initial_runs=40).config().runs_of("unprotected-intersection") == 40
