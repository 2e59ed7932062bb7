"""`evoeye explain` end to end on a tiny batch: simulate, ingest, explain, resume, stats."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.paths import DataRoot
from evoeye.sim.counterfactual import VARIANTS
from evoeye.store import Warehouse
from evoeye.store.attribution import ATTRIBUTION_TABLE, read_attribution

runner = CliRunner(env={"COLUMNS": "200"})


def invoke(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.output


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory) -> DataRoot:
    root = DataRoot.resolve(tmp_path_factory.mktemp("explain") / "data")
    invoke("simulate", "--scenario", "unprotected-intersection", "--n", "6", "--seed", "3",
           "--root", str(root.path))
    invoke("ingest", "--root", str(root.path))
    return root


def collisions(root: DataRoot) -> list[dict]:
    return Warehouse(root).sql(
        "SELECT scenario_id, log_path FROM scenarios WHERE collided ORDER BY scenario_id"
    ).to_pylist()


def test_explain_stores_every_variant_resumes_and_then_has_nothing_left(batch: DataRoot) -> None:
    runs = collisions(batch)
    assert len(runs) >= 2, "the tiny batch needs two collision runs"
    out = invoke("explain", "--root", str(batch.path), "--limit", "1", "--workers", "1")
    assert "1 runs explained, 0 not" in out
    assert read_attribution(batch).num_rows == len(VARIANTS)
    # as if killed after the first run: the next call explains only the rest
    out = invoke("explain", "--root", str(batch.path), "--workers", "2")
    assert f"explaining {len(runs) - 1} collision runs" in out
    table = read_attribution(batch)
    assert table.num_rows == len(VARIANTS) * len(runs)
    assert set(table.column("scenario_id").to_pylist()) == {r["scenario_id"] for r in runs}
    assert "root causes of collisions" in out
    parts = sorted(batch.table_dir(ATTRIBUTION_TABLE).glob("*.parquet"))
    out = invoke("explain", "--root", str(batch.path))
    assert "nothing to explain" in out
    assert sorted(batch.table_dir(ATTRIBUTION_TABLE).glob("*.parquet")) == parts
    shares = Warehouse(batch).sql("SELECT sum(share) AS s, count(DISTINCT scenario_id) AS n "
                                  "FROM run_attribution").to_pylist()[0]
    assert shares["s"] == pytest.approx(len(runs)) and shares["n"] == len(runs)
    stats = invoke("warehouse", "stats", "--root", str(batch.path))
    assert "root causes of collisions" in stats and "unprotected-intersection" in stats


def test_explain_one_log_reads_its_spec_and_stores_nothing(batch: DataRoot) -> None:
    run = collisions(batch)[0]
    before = read_attribution(batch).num_rows
    out = invoke("explain", str(Path(batch.path) / run["log_path"]))
    assert run["scenario_id"] in out
    assert out.count("✓") + out.count("✗") >= len(VARIANTS)
    assert "cause share %" in out  # shares in whole percent, not fractions
    assert re.search(r"\b(perception|prediction|planning|control|compound) (50|100|33|25)\b",
                     out)
    assert read_attribution(batch).num_rows == before
    safe = Warehouse(batch).sql("SELECT log_path FROM scenarios WHERE NOT collided LIMIT 1")
    out = invoke("explain", str(Path(batch.path) / safe.column("log_path")[0].as_py()))
    assert "nothing to explain" in out
