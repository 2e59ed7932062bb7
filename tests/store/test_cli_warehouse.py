"""`evoeye ingest`, `evoeye sql`, `evoeye warehouse stats` through the Typer app."""

from __future__ import annotations

import csv
import io

import orjson
import pytest
from typer.testing import CliRunner

import evoeye.cli.warehouse  # noqa: F401  (registers the commands)
from evoeye.cli.app import app
from evoeye.cli.errors import ExitCode
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
    assert result.exit_code == ExitCode.PARTIAL, result.output  # one log quarantined
    assert "quarantined" in result.output and "cli-bad.mcap" in result.output
    assert "creating a new warehouse" in result.output
    assert "ingest: 100%" in result.stderr and "3/3 [" in result.stderr  # the progress bar
    assert "log/s]" in result.stderr or "s/log]" in result.stderr
    return root


def test_ingest_twice_reports_nothing_new(ingested: DataRoot) -> None:
    result = runner.invoke(app, ["ingest", "--root", str(ingested.path)])
    assert result.exit_code == ExitCode.OK  # nothing new quarantined
    assert "creating a new warehouse" not in result.output
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
    assert result.exit_code == ExitCode.USER_ERROR and "nope" in result.output
    assert "Traceback" not in result.output


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
    assert result.exit_code == ExitCode.USER_ERROR and "another process" in result.output
    assert "hint:" in result.output


@pytest.mark.parametrize("query", [
    "ATTACH '{duckdb}' AS w; CREATE TABLE w.evil AS SELECT 1 AS x",
    "ATTACH '{duckdb}' AS w; DROP VIEW w.frames",
    "COPY (SELECT * FROM scenarios) TO '{root}/leak.csv'",
    "COPY (SELECT * FROM scenarios) TO '{root}/warehouse/leak.csv'",
    "SELECT * FROM read_csv('/etc/passwd')",
    "SELECT * FROM read_parquet('{root}/warehouse/../leak/*.parquet')",
    "INSTALL httpfs",
    "SET enable_external_access = true; SELECT * FROM read_csv('/etc/passwd')",
    "CREATE TABLE t AS SELECT 1 AS x",
])
def test_sql_is_read_only(ingested: DataRoot, query: str) -> None:
    catalog = ingested.duckdb_file.read_bytes()
    text = query.format(duckdb=ingested.duckdb_file, root=ingested.path)
    result = runner.invoke(app, ["sql", text, "--root", str(ingested.path)])
    assert result.exit_code == ExitCode.USER_ERROR, result.output
    assert "error:" in result.output and "Traceback" not in result.output
    assert ingested.duckdb_file.read_bytes() == catalog
    assert not list(ingested.path.rglob("leak*"))
    # the views still work, for this and any other client
    ok = runner.invoke(app, ["sql", "SELECT count(*) AS n FROM frames", "--root",
                             str(ingested.path), "--format", "csv"])
    assert ok.exit_code == 0 and ok.output.splitlines() == ["n", "60"]


def test_sql_allow_files_reads_files_but_still_cannot_write(ingested: DataRoot) -> None:
    other = ingested.path.parent / "other.csv"
    other.write_text("a,b\n1,2\n")
    query = f"SELECT * FROM read_csv('{other}')"
    refused = runner.invoke(app, ["sql", query, "--root", str(ingested.path)])
    assert refused.exit_code == ExitCode.USER_ERROR and "--allow-files" in refused.output
    allowed = runner.invoke(app, ["sql", query, "--root", str(ingested.path), "--allow-files",
                                  "--format", "csv"])
    assert allowed.exit_code == 0 and allowed.output.splitlines() == ["a,b", "1,2"]
    copy = runner.invoke(app, ["sql", f"COPY (SELECT 1) TO '{other}.out'", "--allow-files",
                               "--root", str(ingested.path)])
    assert copy.exit_code == ExitCode.USER_ERROR and not other.with_suffix(".csv.out").exists()


@pytest.mark.parametrize("command", [["sql", "SELECT 1"], ["warehouse", "stats"]])
def test_read_commands_name_a_missing_root(tmp_path, command: list[str]) -> None:
    missing = tmp_path / "nowhere"
    result = runner.invoke(app, [*command, "--root", str(missing)])
    assert result.exit_code == ExitCode.USER_ERROR
    assert f"no data root at {missing}" in result.output.replace("\n", "")
    assert not missing.exists()


def test_tables_keep_identifiers_whole_in_a_pipe(ingested: DataRoot) -> None:
    result = CliRunner(env={"COLUMNS": "40"}).invoke(
        app, ["warehouse", "stats", "--root", str(ingested.path)])
    assert result.exit_code == 0
    assert "highway-cut-in" in result.output and "…" not in result.output
