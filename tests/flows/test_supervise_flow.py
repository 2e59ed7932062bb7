"""The supervise flow end to end through Prefect: one task per run, the report and an artifact."""

from __future__ import annotations

from pathlib import Path

import pytest

from evoeye.batch import plan_uniform, run_batch
from evoeye.evaluation.supervision.summary import ROW_FIELDS
from evoeye.evaluation.supervision.triggers import ORACLE_LEADS_S
from evoeye.paths import DataRoot
from evoeye.store import ingest
from flows.supervise import SuperviseParams, supervise_flow

SCENARIO = "unprotected-intersection"


@pytest.fixture
def root(tmp_path: Path) -> DataRoot:
    """12 ingested runs to calibrate on, a batch of 2 held-out runs to supervise and 2 more
    to choose operating points on."""
    root = DataRoot.resolve(tmp_path / "data")
    run_batch(plan_uniform(SCENARIO, 12, 3), root)
    ingest(root)
    run_batch(plan_uniform(SCENARIO, 2, 9, batch="held"), root)
    run_batch(plan_uniform(SCENARIO, 2, 11, batch="sel"), root)
    return root


def test_supervise_flow_writes_the_report_and_an_artifact(prefect_server: None,
                                                          root: DataRoot, tmp_path) -> None:
    from prefect.client.orchestration import get_client

    params = SuperviseParams(root=str(root.path), scenarios=[SCENARIO], batch="held",
                             baselines=["ttc"], fprs=[0.05, 0.01], workers=1,
                             report_name="flow", docs=str(tmp_path / "docs"),
                             select_batch="sel")
    out = supervise_flow(params)
    (summary,) = out["summaries"]
    assert summary["runs"] == 2 and not summary["errors"]
    assert summary["rows"] and all(tuple(r) == ROW_FIELDS for r in summary["rows"])
    assert {r["trigger"] for r in summary["rows"]} == {"ttc"}  # the oracle is no row …
    assert [o["lead_s"] for o in summary["oracle"]] == sorted(ORACLE_LEADS_S)  # … but a curve
    assert summary["operating_points"] == "validation" and summary["selection_runs"] == 2
    records = list(Path(summary["folder"]).glob("runs/*.json"))
    assert len(records) == 2
    folder = Path(out["report_dir"])
    assert {p.name for p in folder.iterdir()} == {"supervision.md", "report.html", "report.json"}
    assert (tmp_path / "docs" / f"supervision-{SCENARIO}.svg").exists()
    with get_client(sync_client=True) as client:
        artifacts = client.read_artifacts()
    (artifact,) = [a for a in artifacts if a.key == "evoeye-supervision"]
    assert "ttc: operating curve" in artifact.data


def test_bad_parameters_are_refused_before_anything_runs() -> None:
    with pytest.raises(ValueError, match="unknown baseline"):
        SuperviseParams(batch="b", baselines=["ttc", "nope"])
    with pytest.raises(ValueError, match="not a plain name"):
        SuperviseParams(batch="../b")
    with pytest.raises(ValueError, match="logs"):
        SuperviseParams(batch="b", logs="some")
    with pytest.raises(ValueError, match="select_batch is the batch"):
        SuperviseParams(batch="b", select_batch="b")
    with pytest.raises(ValueError, match="unknown fallback"):
        SuperviseParams(batch="b", fallback_preset="gentle")
    with pytest.raises(ValueError, match="tyres"):
        SuperviseParams(batch="b", decel_mps2=12.0)


def test_the_flow_brakes_with_the_production_fallback_unless_told_otherwise() -> None:
    from evoeye.sim.supervisor import FALLBACKS

    assert SuperviseParams(batch="b").fallback == FALLBACKS["production"]
    assert SuperviseParams(batch="b", fallback_preset="comfort").fallback == FALLBACKS["comfort"]
    changed = SuperviseParams(batch="b", fallback_preset="comfort", hold_s=2.0).fallback
    assert (changed.decel_mps2, changed.hold_s) == (6.0, 2.0)
