"""`evoeye demo` end to end, small: the plain-words summary, then where the results are."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.evaluation.headline import scenario_words
from evoeye.paths import DataRoot
from evoeye.results.demo import plan

pytestmark = pytest.mark.slow  # simulates 16 runs and evolves twice: minutes under load


def test_demo_prints_the_summary_per_scenario_and_where_the_results_are(tmp_path) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    res = CliRunner(env={"COLUMNS": "200"}).invoke(
        app, ["demo", "--root", str(root.path), "--n", "8", "--evolve-runs", "1"])
    assert res.exit_code == 0, res.output
    text = res.stdout
    assert "Operating point: each monitor's alarm threshold is set on validation runs" in text
    shipped = plan()[0]  # every scenario that ships a demo monitor
    for scenario in shipped:
        assert f"{scenario_words(scenario)} — " in text
    assert text.count("Best rule-based baseline (") == text.count("Evolution: ") == len(shipped)
    assert text.count("  In the loop: ") >= len(shipped)  # measured, or said why not
    where = text.split("Where the results are:")[1]
    assert str(root.runs) in where and str(root.path / "reports" / "demo") in where
    summary = (root.path / "reports" / "demo" / "summary.md").read_text()
    assert summary.strip() in text
