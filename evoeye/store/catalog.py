"""DuckDB over the warehouse Parquet: the connection every reader uses, and the catalog file.

Readers never open the DuckDB file for writing and take no lock: `Warehouse.connect()` gives an
in-memory DuckDB whose views read the Parquet parts directly (inside `shared_connections()`, a
cursor of one such database per warehouse state); `Warehouse.read_only_sql` runs a user's
query there with reads only and, by default, external access off except for the warehouse
folder. The file `<root>/warehouse/evoeye.duckdb` holds the same views for the DuckDB CLI and
other tools; only the ingester (under the writer lock) rewrites it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import duckdb
import pyarrow as pa

from evoeye.paths import DataRoot
from evoeye.store.connections import connection
from evoeye.store.parts import PartStore
from evoeye.store.schema import (
    DDL_SCHEMA,
    DERIVED_TABLES,
    PARTITION_KEYS,
    TABLES,
    create_declared_tables,
)
from evoeye.store.sqlfiles import parts_macros, query, view_scripts

READ_ONLY_STATEMENTS = frozenset({duckdb.StatementType.SELECT, duckdb.StatementType.EXPLAIN})
PART_GLOB = "/".join(["*"] * len(PARTITION_KEYS) + ["*.parquet"])  # */*/*.parquet
CODE_VIEWS = ("attribution",)  # the derived tables' views the view scripts read (run_attribution)


def _string_literal(text: str) -> str:
    """A SQL string literal. Used for the Parquet folder paths only, which DuckDB cannot bind
    as parameters inside a view definition."""
    return "'" + text.replace("'", "''") + "'"


def _parquet_view_sql(table: str, table_dir: Path, has_parts: bool) -> str:
    """The base view `<table>_parquet` over every part of `table`, or the empty declared table.

    The parts share one schema (a warehouse holds one layout: `PartStore.check_layout`), so
    DuckDB reads it from one file and need not union the schemas of every part each time a
    view or query is bound (that took most of a connection's time over a few dozen parts)."""
    if not has_parts:
        source = f"{DDL_SCHEMA}.{table}"
    else:
        hive_types = ", ".join(f"{_string_literal(k)}: 'VARCHAR'" for k in PARTITION_KEYS)
        source = (
            f"read_parquet({_string_literal(str(table_dir / PART_GLOB))}, "
            f"hive_partitioning = true, hive_types = {{{hive_types}}})"
        )
    keys = ", ".join(PARTITION_KEYS)  # hive keys come last, in DDL order
    return (
        f"CREATE OR REPLACE VIEW {table}_parquet AS "
        f"SELECT * EXCLUDE ({keys}), {keys} FROM {source}"
    )


def _derived_view_sql(table: str, table_dir: Path, has_parts: bool) -> str:
    """The view `<table>` over every flat part of a derived table, read by its macro
    `<table>_parts` (warehouse/parts.sql), or its empty declared table."""
    source = f"{DDL_SCHEMA}.{table}"
    if has_parts:
        source = f"{table}_parts({_string_literal(str(table_dir / '*.parquet'))})"
    return f"CREATE OR REPLACE VIEW {table} AS SELECT * FROM {source}"


def parts_present(root: DataRoot) -> tuple[bool, ...]:
    """Whether each table (TABLES, then DERIVED_TABLES) has a part: the views depend on nothing
    else of the warehouse's state. WarehouseLayoutError for a warehouse of another layout."""
    PartStore(root).check_layout()
    return (*(any(root.table_dir(t).glob(PART_GLOB)) for t in TABLES),
            *(any(root.table_dir(t).glob("*.parquet")) for t in DERIVED_TABLES))


def install_views(con: duckdb.DuckDBPyConnection, root: DataRoot,
                  present: tuple[bool, ...] | None = None, *, for_user: bool = False) -> None:
    """Create the declared tables, the Parquet base views, the derived tables' macros and views
    and every view script on `con`, for the tables `present` (default: as they are now,
    `parts_present`). The derived tables' views are the user's (`for_user`: `evoeye sql`, the
    DuckDB file) but those the view scripts read (CODE_VIEWS): binding a view reads its parts'
    footers, and the code reads those tables by key (`derived.read_parts`) instead."""
    present = parts_present(root) if present is None else present
    create_declared_tables(con)
    for table, has_parts in zip(TABLES, present[:len(TABLES)], strict=True):
        con.execute(_parquet_view_sql(table, root.table_dir(table), has_parts))
    con.execute(parts_macros())
    for table, has_parts in zip(DERIVED_TABLES, present[len(TABLES):], strict=True):
        if for_user or table in CODE_VIEWS:
            con.execute(_derived_view_sql(table, root.table_dir(table), has_parts))
    for _, script in view_scripts():
        con.execute(script)


class ReadOnlyQueryError(ValueError):
    """A query given to `Warehouse.read_only_sql` that is not a read."""


def _lock_down(con: duckdb.DuckDBPyConnection, readable: Path) -> None:
    """No file outside `readable`, no ATTACH, no INSTALL, and no way to turn that back on."""
    con.execute("SET allowed_directories = ?", [[str(readable) + "/"]])
    con.execute("SET enable_external_access = false")
    con.execute("SET lock_configuration = true")


class Warehouse:
    """Read access to the warehouse of one data root."""

    def __init__(self, root: DataRoot) -> None:
        self.root = root

    def connect(self) -> duckdb.DuckDBPyConnection:
        """An in-memory DuckDB with the warehouse views the code reads (every one but the
        appended tables' views `read_only_sql` adds, `install_views`); the caller closes it.
        Inside `shared_connections()`, a connection to the block's database of the warehouse
        in its present state (`evoeye.store.connections`)."""
        present = parts_present(self.root)
        return connection(("views", str(self.root.path), present),
                          lambda: self._new(present))

    def _new(self, present: tuple[bool, ...],
             for_user: bool = False) -> duckdb.DuckDBPyConnection:
        """A new in-memory DuckDB with the views of the tables `present`."""
        con = duckdb.connect()
        try:
            install_views(con, self.root, present, for_user=for_user)
        except BaseException:
            con.close()
            raise
        return con

    def sql(self, text: str, params: dict[str, Any] | list[Any] | None = None) -> pa.Table:
        """Run any SQL against the warehouse views, with bound parameters; the result as Arrow."""
        con = self.connect()
        try:
            return con.sql(text, params=params).to_arrow_table()
        finally:
            con.close()

    def read_only_sql(self, text: str, *, allow_files: bool = False) -> pa.Table:
        """Run a user's query: SELECT / EXPLAIN statements only (ReadOnlyQueryError otherwise),
        and unless `allow_files`, no file but the warehouse's own Parquet (duckdb's
        PermissionException otherwise); the last statement's result as Arrow. Always a
        database of its own: locking it down locks the whole database."""
        con = self._new(parts_present(self.root), for_user=True)
        try:
            statements = con.extract_statements(text)
            refused = sorted({s.type.name for s in statements} - {t.name for t in
                                                                   READ_ONLY_STATEMENTS})
            if refused or not statements:
                raise ReadOnlyQueryError(
                    f"the warehouse is read-only here: only SELECT and EXPLAIN are run, not "
                    f"{', '.join(refused) or 'an empty query'}")
            if not allow_files:
                _lock_down(con, self.root.warehouse)
            for statement in statements[:-1]:
                con.execute(statement.query).fetchall()
            return con.sql(statements[-1].query).to_arrow_table()
        finally:
            con.close()

    def query(self, name: str, **params: Any) -> pa.Table:
        """Run `warehouse/queries/<name>.sql` with `$name` parameters bound."""
        return self.sql(query(name), params or None)


def write_catalog(root: DataRoot) -> None:
    """Rewrite the views of `<root>/warehouse/evoeye.duckdb`. Call only under the writer lock."""
    root.warehouse.mkdir(parents=True, exist_ok=True)
    con = duckdb.connect(str(root.duckdb_file))
    try:
        install_views(con, root, for_user=True)
        con.execute("CHECKPOINT")
    finally:
        con.close()
