"""Contracts: Parquet == DDL; every view, macro and query runs, on an empty warehouse too."""

from __future__ import annotations

import subprocess
import sys

import duckdb
import numpy as np
import pyarrow.parquet as pq
import pytest

from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest
from evoeye.store.attribution import AttributionRow, write_attribution
from evoeye.store.feedback import (
    FeedbackRows,
    RoundRow,
    write_committee,
    write_feedback,
    write_round,
)
from evoeye.store.schema import (
    DERIVED_TABLES,
    PARTITION_KEYS,
    TABLES,
    canonical_schema,
    file_schema,
    table_schema,
)
from evoeye.store.scores import ScoreRows, write_scores
from evoeye.store.sqlfiles import query, query_names

# Sample parameters for every file in warehouse/queries (a new query must be added here).
QUERY_PARAMS = {
    "committed_runs": {},
    "committed_ids": {"ids": ["c-0", "c-1"]},
    "campaign_records": {"ids": ["c-0", "c-1"]},
    "dataset_stats": {"horizon_s": 3.0, "seed": 0, "train_frac": 0.5, "val_frac": 0.125,
                      "test_batch": None},
    "run_frames": {"scenario_id": "c-0"},
    "select_runs": {
        "logical_scenario": "highway-cut-in", "split": None, "source": None, "min_round": 0,
        "max_round": None, "collided": None, "status": "ok", "seed": 0, "train_frac": 0.5,
        "val_frac": 0.125, "test_batch": None,
    },
    "window_runs": {},
    "collision_runs": {"logical_scenario": None, "batch": None, "software_version": "other",
                       "variants": 5},
    "attribution_shares": {"logical_scenario": "highway-cut-in"},
    "hard_set": {  # every run in test; a monitor scoring 0 everywhere misses every unsafe frame
        "monitor_version": "m", "threshold": 0.5, "logical_scenario": "highway-cut-in",
        "horizon_s": 3.0, "seed": 0, "train_frac": 0.0, "val_frac": 0.0, "test_batch": None,
    },
    "robust_hard_set": {  # one monitor scoring 0 everywhere misses every unsafe frame
        "monitor_versions": ["m"], "thresholds": [0.5], "logical_scenario": "highway-cut-in",
        "horizon_s": 3.0, "seed": 0, "train_frac": 0.0, "val_frac": 0.0, "test_batch": None,
    },
    "initial_split_stats": {"logical_scenario": "highway-cut-in", "horizon_s": 3.0, "seed": 0,
                            "train_frac": 0.5, "val_frac": 0.125, "test_batch": None},
    "audit_attribution": {"scenario_ids": ["c-0", "c-1"]},
    "initial_records": {"scenario": "highway-cut-in", "seed": 0, "train_frac": 1.0,
                        "val_frac": 0.0, "test_batch": "b1"},
    "run_outcomes": {"logical_scenario": "highway-cut-in"},
    "predictability_runs": {"scenario": "highway-cut-in", "batch": None, "ads": "default"},
    "logical_scenarios": {},
    # queries over a derived table's parts: $glob is bound to them (DERIVED_PARTS)
    "monitor_scores_rows": {"version": None},
    "monitor_scores_scenarios": {"version": "m-1"},
    "feedback_rows": {"version": "m-1", "mode": "raw"},
    "campaign_rounds_rows": {"campaign_id": None},
    "committee_rows": {"campaign_id": "evo-x"},
    "attribution_rows": {"version": "v"},
}
DERIVED_PARTS = {"monitor_scores_rows": "monitor_scores", "monitor_scores_scenarios":
                 "monitor_scores", "feedback_rows": "feedback",
                 "campaign_rounds_rows": "campaign_rounds", "committee_rows": "committee",
                 "attribution_rows": "attribution"}


@pytest.fixture
def filled(root: DataRoot, add_run) -> DataRoot:
    add_run("c-0", n_frames=6, collision_frame=4, seed=1)
    add_run("c-1", n_frames=5, seed=2, logical_scenario="unprotected-intersection", batch="b1")
    ingest(root)
    write_attribution(root, [
        AttributionRow("highway-cut-in", "c-0", "v", variant, variant != "oracle_planning", None,
                       1.0, False)
        for variant in ("careful_driver", "oracle_perception", "oracle_prediction",
                        "oracle_planning", "oracle_control")
    ])
    ids = np.array(["c-0", "c-1"], dtype=object)
    write_scores(root, ScoreRows("m", "m-1", "highway-cut-in", ids, np.array([0, 1]),
                                 np.array([0.0, 0.05]), np.array([0.1, 0.9])))
    write_feedback(root, FeedbackRows("highway-cut-in", "m-1", "raw", ids, np.array([0.1, 0.2]),
                                      np.array([4, 5])))
    write_round(root, RoundRow("evo-x", "highway-cut-in", "uniform", 0, 0, "m-1", [], 0, 0.0))
    write_committee(root, "evo-x", 0, ["m-2", "m-3"])
    return root


def test_every_parquet_file_has_the_ddl_schema(filled: DataRoot) -> None:
    for table in TABLES:
        files = list(filled.table_dir(table).rglob("*.parquet"))
        assert files, table
        for path in files:
            written = canonical_schema(pq.read_schema(path))
            assert written == canonical_schema(file_schema(table)), path
            assert not set(PARTITION_KEYS) & set(written.names)  # they live in folder names
            assert path.parent.name.startswith("batch=")
            assert path.parent.parent.name.startswith("logical_scenario=")


@pytest.mark.parametrize("filled_or_empty", ["filled", "empty"])
def test_views_have_the_ddl_schema(filled_or_empty: str, request: pytest.FixtureRequest) -> None:
    root = request.getfixturevalue("filled" if filled_or_empty == "filled" else "root")
    wh = Warehouse(root)
    for table in TABLES:
        got = wh.sql(f"SELECT * FROM {table} LIMIT 0").schema
        assert canonical_schema(got) == canonical_schema(table_schema(table)), table


def _user_views_and_macros(con: duckdb.DuckDBPyConnection) -> tuple[list[str], list[str]]:
    views = [r[0] for r in con.execute(
        "SELECT view_name FROM duckdb_views() WHERE NOT internal AND schema_name = 'main'"
    ).fetchall()]
    macros = [r[0] for r in con.execute(
        "SELECT DISTINCT function_name FROM duckdb_functions() "
        "WHERE function_type = 'table_macro' AND NOT internal"
    ).fetchall()]
    return views, macros


MACRO_ARGS = {
    "frame_labels_h": [1.5],
    "scenario_splits": [7, 0.6, 0.2],
    "dataset_stats_h": [3.0, 0, 0.5, 0.125],
}


@pytest.mark.parametrize("filled_or_empty", ["filled", "empty"])
def test_every_view_and_macro_runs(filled_or_empty: str, request: pytest.FixtureRequest) -> None:
    root = request.getfixturevalue("filled" if filled_or_empty == "filled" else "root")
    con = Warehouse(root).connect()
    try:
        views, macros = _user_views_and_macros(con)
        assert {"scenarios", "frames", "frame_features", "runtime_frames", "frame_labels",
                "splits", "dataset_stats"} <= set(views)
        parts = {f"{table}_parts": table for table in DERIVED_TABLES}  # warehouse/parts.sql
        assert set(macros) == set(MACRO_ARGS) | set(parts)
        for view in views:
            rows = con.execute(f"SELECT * FROM {view}").fetchall()
            assert (len(rows) > 0) == (filled_or_empty == "filled") or view == "dataset_stats"
        for macro, args in MACRO_ARGS.items():
            marks = ", ".join("?" * len(args))
            con.execute(f"SELECT * FROM {macro}({marks})", args).fetchall()
        for macro, table in parts.items() if filled_or_empty == "filled" else ():
            glob = str(root.table_dir(table) / "*.parquet")
            rows = con.sql(f"SELECT * FROM {macro}($glob)", params={"glob": glob})
            assert rows.to_arrow_table().to_pylist() == Warehouse(root).read_only_sql(
                f"SELECT * FROM {table}").to_pylist() != []  # the user's view reads through it
    finally:
        con.close()


@pytest.mark.parametrize("name", sorted(QUERY_PARAMS))
def test_every_query_runs(name: str, filled: DataRoot) -> None:
    con = Warehouse(filled).connect()
    try:
        con.register("selected_runs", con.sql("SELECT scenario_id FROM scenarios"))
        con.register("monitor_scores", con.sql(
            "SELECT scenario_id, frame, 'm' AS monitor_version, 0.0 AS score FROM frames"))
        params = dict(QUERY_PARAMS[name])
        if name in DERIVED_PARTS:
            params["glob"] = str(filled.table_dir(DERIVED_PARTS[name]) / "*.parquet")
        rows = con.sql(query(name), params=params or None).fetchall()
        assert rows, name
    finally:
        con.close()


def test_every_query_file_is_covered() -> None:
    assert set(query_names()) == set(QUERY_PARAMS)


def test_catalog_file_holds_the_views_for_other_tools(filled: DataRoot) -> None:
    con = duckdb.connect(str(filled.duckdb_file), read_only=True)
    try:
        tables = {r[0] for r in con.execute(
            "SELECT table_name FROM information_schema.tables WHERE table_schema = 'main'"
        ).fetchall()}
        n = con.execute("SELECT count(*) FROM frames").fetchone()[0]
    finally:
        con.close()
    assert {"scenarios", "frames", "frame_labels", "splits"} <= tables and n == 11


def test_catalog_busy_elsewhere_does_not_lose_data(filled: DataRoot, add_run) -> None:
    add_run("c-2", n_frames=3, seed=3)
    # another process (e.g. a DuckDB CLI session) holds the catalog file open read-write
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD_CATALOG, str(filled.duckdb_file)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "holding"
        report = ingest(filled)
    finally:
        holder.communicate("done\n", timeout=30)
    assert report.ingested == ["c-2"]
    assert report.catalog_error is not None and "evoeye.duckdb" in report.catalog_error
    assert Warehouse(filled).sql("SELECT count(*) AS n FROM scenarios").column("n")[0].as_py() == 3


HOLD_CATALOG = """
import sys, duckdb
con = duckdb.connect(sys.argv[1])
print("holding", flush=True)
sys.stdin.readline()
con.close()
"""
