"""`evoeye ingest`, `evoeye sql`, `evoeye warehouse stats` through the Typer app."""

from __future__ import annotations

import csv
import io

import orjson
import pytest
from typer.testing import CliRunner

import evoeye.cli.warehouse  # noqa: F401  (registers the commands)
from evoeye.cli.app import app
from evoeye.paths import DataRoot
from evoeye.store import WriterLock

runner = CliRunner(env={"COLUMNS": "200"})


@pytest.fixture
def ingested(root: DataRoot, add_run) -> DataRoot:
    add_run("cli-0", n_frames=40, collision_frame=30, seed=1)
    add_run("cli-1", n_frames=20, seed=2)
    bad = add_run("cli-bad", n_frames=5, seed=3)
    bad.write_bytes(bad.read_bytes()[:200])
    result = runner.invoke(app, ["ingest", "--root", str(root.path)])
    assert result.exit_code == 0, result.output
    assert "quarantined" in result.output and "cli-bad.mcap" in result.output
    return root


def test_ingest_twice_reports_nothing_new(ingested: DataRoot) -> None:
    result = runner.invoke(app, ["ingest", "--root", str(ingested.path)])
    assert result.exit_code == 0
    assert "runs ingested" in result.output and "already in the warehouse" in result.output
    lines = {line.split("│")[1].strip(): line.split("│")[2].strip()
             for line in result.output.splitlines() if line.count("│") == 3}
    assert lines["runs ingested"] == "0" and lines["already in the warehouse"] == "2"


def test_sql_formats(ingested: DataRoot) -> None:
    query = "SELECT scenario_id, n_frames, params[1:2] AS p FROM scenarios ORDER BY scenario_id"
    base = ["sql", query, "--root", str(ingested.path)]
    as_json = orjson.loads(runner.invoke(app, [*base, "--format", "json"]).output)
    assert [r["scenario_id"] for r in as_json] == ["cli-0", "cli-1"]
    assert as_json[0]["n_frames"] == 40 and len(as_json[0]["p"]) == 2
    rows = list(csv.reader(io.StringIO(runner.invoke(app, [*base, "--format", "csv"]).output)))
    assert rows[0] == ["scenario_id", "n_frames", "p"] and rows[2][:2] == ["cli-1", "20"]
    assert len(orjson.loads(rows[1][2])) == 2  # lists are JSON inside CSV
    table = runner.invoke(app, base).output
    assert "cli-0" in table and "cli-1" in table


def test_sql_error_is_reported(ingested: DataRoot) -> None:
    result = runner.invoke(app, ["sql", "SELECT nope FROM scenarios", "--root",
                                 str(ingested.path)])
    assert result.exit_code == 1 and "nope" in result.output


def test_stats_prints_the_dataset_table(ingested: DataRoot) -> None:
    result = runner.invoke(app, ["warehouse", "stats", "--root", str(ingested.path),
                                 "--train-frac", "1.0", "--val-frac", "0.0"])
    assert result.exit_code == 0, result.output
    row = next(line for line in result.output.splitlines() if "highway-cut-in" in line)
    cells = [c.strip() for c in row.split("│") if c.strip()]
    # both runs train; 1 violation of 2; 50 eligible frames (cli-0's 10 from its collision on
    # are not); frames 0 < 1.5 - t <= 3 -> 30 unsafe
    assert cells == ["highway-cut-in", "train", "2", "1 (50.0%)", "50", "30 (60.0%)", "0"]


def test_ingest_refused_while_another_writer_holds_the_lock(root: DataRoot) -> None:
    with WriterLock(root.writer_lock):
        result = runner.invoke(app, ["ingest", "--root", str(root.path)])
    assert result.exit_code == 1 and "another process" in result.output
