"""Every table, view and macro docs/warehouse.md names exists, and answers `evoeye sql` and plain
duckdb on the catalog file; every view the warehouse installs is named there."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import duckdb
import numpy as np
import pytest
from typer.testing import CliRunner

import evoeye.cli.warehouse  # noqa: F401  (registers the commands)
from evoeye.cli.app import app
from evoeye.paths import DataRoot
from evoeye.store import Warehouse
from evoeye.store.attribution import AttributionRow, write_attribution
from evoeye.store.feedback import (
    FeedbackRows,
    RoundRow,
    write_committee,
    write_feedback,
    write_round,
)
from evoeye.store.ingest import refresh_catalog
from evoeye.store.schema import DERIVED_TABLES, declared_schema
from evoeye.store.scores import ScoreRows, write_scores

DOC = Path(__file__).resolve().parents[2] / "docs" / "warehouse.md"
HEADERS = ("table", "view or macro")  # the first header cell of the tables that name them
runner = CliRunner(env={"COLUMNS": "200"})


def documented() -> dict[str, list[str] | None]:
    """Each name in the first column of the doc's tables of tables, views and macros: a
    macro's parameter names (`name(a, b := NULL)`), None for a table or view."""
    names: dict[str, list[str] | None] = {}
    header = None
    for line in DOC.read_text(encoding="utf-8").splitlines():
        if not line.startswith("|"):
            header = None
            continue
        first = line.split("|")[1].strip()
        if header is None:
            header = first
        elif header in HEADERS and not set(first) <= set("-: "):
            for name, call, args in re.findall(r"`(\w+)(\(([^)]*)\))?`", first):
                names[name] = ([a.split(":=")[0].strip() for a in args.split(",") if a.strip()]
                               if call else None)
    return names


def installed(wh: Warehouse) -> tuple[set[str], dict[str, list[str]]]:
    """The views a user's query sees (`evoeye sql`), and the table macros with their
    parameters."""
    views = wh.read_only_sql("SELECT view_name FROM duckdb_views() "
                             "WHERE NOT internal AND schema_name = 'main'").column(0)
    macros = wh.read_only_sql("SELECT function_name, parameters FROM duckdb_functions() "
                              "WHERE function_type = 'table_macro' AND NOT internal")
    return set(views.to_pylist()), dict(zip(*(c.to_pylist() for c in macros.columns),
                                            strict=True))


def _count(con: duckdb.DuckDBPyConnection, relation: str) -> int:
    return con.sql(f"SELECT count(*) FROM {relation}").fetchall()[0][0]


@pytest.fixture
def full(root: DataRoot, add_run: Callable[..., Path]) -> DataRoot:
    """Two ingested runs and a row in every table later stages append to, written after the
    ingest, as evaluate, explain and a campaign write them."""
    add_run("doc-0", n_frames=40, collision_frame=30, seed=1)
    add_run("doc-1", n_frames=20, seed=2)
    assert runner.invoke(app, ["ingest", "--root", str(root.path)]).exit_code == 0
    ids = np.array(["doc-0"], dtype=object)
    # the first scores refresh the catalog file themselves (an evaluation writes no other table)
    write_scores(root, ScoreRows("fusion", "fusion-a", "highway-cut-in", ids, np.array([0]),
                                 np.array([0.0]), np.array([0.5])))
    write_feedback(root, FeedbackRows("highway-cut-in", "fusion-a", "raw", ids, np.array([0.2]),
                                      np.array([10])))
    write_round(root, RoundRow("evo-1", "highway-cut-in", "evoeye", 0, 0, "fusion-a", [], 0, 0.0))
    write_committee(root, "evo-1", 0, ["fusion-b", "fusion-c"])
    write_attribution(root, [AttributionRow("highway-cut-in", "doc-0", "0.0", variant, False,
                                            None, 1.0, None)
                             for variant in ("oracle_perception", "oracle_prediction",
                                             "oracle_planning", "oracle_control")])
    return root


def test_the_doc_names_every_view_and_table_macro_and_nothing_else(root: DataRoot) -> None:
    names = documented()
    views, macros = installed(Warehouse(root))
    assert {n for n, args in names.items() if args is None} == views
    assert {n: args for n, args in names.items() if args is not None} == macros
    assert set(DERIVED_TABLES) <= views


def test_every_documented_relation_answers_evoeye_sql_and_duckdb(full: DataRoot) -> None:
    relations = [n for n, args in documented().items() if args is None]
    for name in relations:
        result = runner.invoke(app, ["sql", f"SELECT * FROM {name} LIMIT 1", "--root",
                                     str(full.path), "--format", "json"])
        assert result.exit_code == 0, (name, result.output)
    con = duckdb.connect(str(full.duckdb_file), read_only=True)
    try:
        assert _count(con, "monitor_scores") == 1
        for name in relations:
            con.sql(f"SELECT * FROM {name} LIMIT 1").fetchall()
    finally:
        con.close()
    refresh_catalog(full)  # what a campaign does when it ends
    con = duckdb.connect(str(full.duckdb_file), read_only=True)
    try:
        counts = {t: _count(con, t) for t in DERIVED_TABLES}
    finally:
        con.close()
    assert counts == {"attribution": 4, "monitor_scores": 1, "feedback": 1, "campaign_rounds": 1,
                      "committee": 1}


def test_the_derived_views_have_the_declared_columns(full: DataRoot) -> None:
    for table in DERIVED_TABLES:
        assert Warehouse(full).read_only_sql(f"SELECT * FROM {table}").schema.names == \
            declared_schema(table).names, table
    rows = Warehouse(full).sql("SELECT cause, share FROM run_attribution ORDER BY cause")
    assert rows.to_pylist() == [{"cause": m, "share": 0.25}
                                for m in ("control", "perception", "planning", "prediction")]
