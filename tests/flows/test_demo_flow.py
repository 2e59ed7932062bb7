"""`make demo`'s flow end to end, small: the summary answers how many collisions are warned of,
how early and at how many false alarms per hour, and says where everything is."""

from __future__ import annotations

from pathlib import Path

import pytest

from evoeye.evaluation.headline import scenario_words
from evoeye.paths import DataRoot
from evoeye.results import demo as steps
from flows.demo import DemoParams, demo_flow

pytestmark = pytest.mark.slow  # simulates 24 runs and evolves twice: minutes under load


def test_the_demo_flow_ends_with_its_summary_and_where_the_results_are(
        prefect_server, tmp_path, latest_artifact, flow_run_names) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    out = demo_flow(DemoParams(root=str(root.path), n=12, evolve_runs=2, workers=2))
    text = out["summary"]
    assert text.startswith("evoeye demo: what the runtime monitor achieves")
    for scenario in steps.plan()[0]:
        block = text.split(f"{scenario_words(scenario)} — ")[1].split("\n\n")[0]
        assert "FusionMonitor warned of " in block and " of safe driving (" in block
        assert "Best rule-based baseline (" in block
        assert "  In the loop: used as the trigger of a 9 m/s² emergency brake" in block
        assert "Evolution: 1 round(s) added 2 runs" in block
        assert "too few to compare" in block  # 12 runs: a handful of test collisions
    paths = dict(out["paths"])
    summary = Path(paths["this summary"])
    assert summary.read_text().strip() == text.strip()
    assert Path(paths["report (Markdown, HTML, JSON)"]).is_file()
    assert "In the loop" in Path(paths["the monitor in the loop (Markdown, HTML, JSON)"]
                                 ).read_text()
    shipped = len(steps.plan()[0])
    assert len(list(root.runs.rglob("*.mcap"))) == shipped * (12 + 2)  # demo runs + the rounds'
    assert text in latest_artifact("evoeye-demo")
    assert flow_run_names(f"demo-{root.path.name}")
    assert flow_run_names(*(f"simulate-{s}-demo-n12" for s in steps.plan()[0])) == sorted(
        f"simulate-{s}-demo-n12" for s in steps.plan()[0])
