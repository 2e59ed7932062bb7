"""The warehouse tables' contracts: the DDL in `schemas/warehouse/` and the Arrow schemas from it.

The DDL is the one place a column is declared. Python never retypes it: the Arrow schema of a
table is what DuckDB reports for the declared (empty) table, so the Parquet files, the views and
the DDL cannot drift apart.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import duckdb
import pyarrow as pa

# The one place that locates the SQL folders (the project is installed editable).
PROJECT_DIR = Path(__file__).resolve().parents[2]
DDL_DIR = PROJECT_DIR / "schemas" / "warehouse"
VIEWS_DIR = PROJECT_DIR / "warehouse" / "views"
QUERIES_DIR = PROJECT_DIR / "warehouse" / "queries"

TABLES = ("scenarios", "frames", "frame_features")
# Tables later stages append to, as flat parts under warehouse/<table>/ (no partitions): explain,
# evaluate and the evolution campaign. Each is read through its macro `<table>_parts(files)`
# (PARTS_SQL): every connection sees all its parts as the view `<table>`.
DERIVED_TABLES = ("attribution", "monitor_scores", "feedback", "campaign_rounds", "committee")
PARTS_SQL = PROJECT_DIR / "warehouse" / "parts.sql"
# Hive partition keys, in folder order: they are columns of the views, not of the files.
PARTITION_KEYS = ("logical_scenario", "batch")
DDL_SCHEMA = "ddl"  # the DuckDB schema holding the declared, always empty, tables

# How the ingested tables' parts are laid out; every part carries it in its Parquet metadata
# (LAYOUT_KEY; parts without it are layout 1). Bump it with any change to their DDL: a
# warehouse holds parts of one layout only (`check_layout`), so the views need not reconcile
# schemas file by file. 1: frame_features arrays as FLOAT[] lists (evoeye <= 0.4.0);
# 2: as little-endian float32 bytes (BLOB); 3: scenarios.ads_profile; 4: scenarios.label_source
# and the frames' message ages (age_*), for recordings imported from other stacks; 5: the actor
# ids other_actor and gt_collision_actor as BIGINT (`evoeye.store.migrate` rewrites layout 4).
LAYOUT_VERSION = 5
MIGRATABLE = (4,)  # layouts whose parts differ from LAYOUT_VERSION's in column types only
LAYOUT_KEY = b"evoeye.warehouse_layout"


class WarehouseLayoutError(RuntimeError):
    """Parts of a warehouse layout this evoeye does not read (LAYOUT_VERSION)."""


def ddl(table: str) -> str:
    """The CREATE TABLE statement of `table`."""
    if table not in TABLES:
        raise KeyError(f"unknown warehouse table {table!r}; known: {TABLES}")
    return (DDL_DIR / f"{table}.sql").read_text(encoding="utf-8")


def create_declared_tables(con: duckdb.DuckDBPyConnection) -> None:
    """Create every declared table, empty, in the `ddl` schema of `con`."""
    con.execute(f"CREATE SCHEMA IF NOT EXISTS {DDL_SCHEMA}")
    con.execute(f"SET schema = '{DDL_SCHEMA}'")
    try:
        for table in TABLES + DERIVED_TABLES:
            con.execute(f"DROP TABLE IF EXISTS {table}")
            con.execute((DDL_DIR / f"{table}.sql").read_text(encoding="utf-8"))
    finally:
        con.execute("SET schema = 'main'")


def _canonical(t: pa.DataType) -> pa.DataType:
    """`t` with list children renamed to Arrow's default and every binary a plain one, so
    DuckDB's, Parquet's and the writers' types agree."""
    if pa.types.is_list(t) or pa.types.is_large_list(t):
        return pa.list_(_canonical(t.value_type))
    if pa.types.is_large_string(t) or pa.types.is_string_view(t):
        return pa.string()
    if pa.types.is_fixed_size_binary(t) or pa.types.is_large_binary(t) \
            or pa.types.is_binary_view(t):
        return pa.binary()  # a BLOB of the DDL, of a fixed width or not
    return t


@cache
def declared_schema(table: str) -> pa.Schema:
    """The Arrow schema of any table declared in `schemas/warehouse/<table>.sql` (ingested or
    derived, e.g. monitor_scores), in DDL order, canonical."""
    path = DDL_DIR / f"{table}.sql"
    if not path.is_file():
        raise KeyError(f"no DDL for table {table!r} in {DDL_DIR}")
    con = duckdb.connect()
    try:
        con.execute(path.read_text(encoding="utf-8"))
        declared = con.sql(f"SELECT * FROM {table} LIMIT 0").to_arrow_table().schema
    finally:
        con.close()
    return canonical_schema(declared)


def table_schema(table: str) -> pa.Schema:
    """The Arrow schema of ingested table `table`, partition keys included, in DDL order."""
    ddl(table)  # refuses a table that is not ingested
    return declared_schema(table)


@cache
def file_schema(table: str) -> pa.Schema:
    """The Arrow schema of one Parquet file of `table`: the declared one minus partition keys."""
    full = table_schema(table)
    return pa.schema([f for f in full if f.name not in PARTITION_KEYS])


def canonical_schema(schema: pa.Schema) -> pa.Schema:
    """`schema` with nullability, metadata and list child names dropped, for comparisons."""
    return pa.schema([pa.field(f.name, _canonical(f.type)) for f in schema])
