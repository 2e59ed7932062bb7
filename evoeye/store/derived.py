"""The tables later stages derive and append to: flat parts under `<root>/warehouse/<table>/`.

monitor_scores (evaluation), feedback, campaign_rounds and committee (evolution) and attribution
(explain) are written one part per write — `part-<utc stamp>-<id>.parquet`, columns as the
table's DDL declares them (temporary file, fsync, rename: a killed write leaves no partial
part) — and read back with a query from `warehouse/queries/` whose `$glob` names the parts,
every value bound, through the table's macro `<table>_parts` (`warehouse/parts.sql`), which
the views use too.
Each table's module keeps its own key and writes under the warehouse writer lock (`lock.py`).

A part holding the rows of one key only (one monitor version's feedback or scores, one
campaign's rounds) is named `<key>--part-…`, so reading one key opens its own parts (and any
unkeyed ones) instead of every part of the table: a campaign rereads its own state each round
while an experiment's other campaigns add thousands of parts.
"""

from __future__ import annotations

import os
import re
import uuid
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import duckdb
import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.atomic import atomic_file, fsync_dir
from evoeye.paths import DataRoot
from evoeye.store.connections import connection
from evoeye.store.schema import canonical_schema, declared_schema
from evoeye.store.sqlfiles import parts_macros, query

PART_SUFFIX = ".parquet"
KEY_SEPARATOR = "--"
KEY = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._+]*(-[A-Za-z0-9._+]+)*$")  # no "--" inside


def part_name(stamp: datetime, key: str | None = None) -> str:
    """A new part's name: `part-<utc stamp>-<8 hex>`, after `<key>--` if the part holds one key's
    rows only (ValueError for a key that could not name a file, or holds "--")."""
    name = f"part-{stamp:%Y%m%dT%H%M%SZ}-{uuid.uuid4().hex[:8]}"
    if key is None:
        return name
    if not KEY.match(key):
        raise ValueError(f"{key!r} cannot key a part: letters, digits, . _ + and single -")
    return f"{key}{KEY_SEPARATOR}{name}"


def part_files(folder: Path, key: str | None = None) -> list[Path]:
    """The parts under `folder` that may hold rows of `key` (its own and the unkeyed), or
    every part."""
    if key is None or not KEY.match(key):
        return sorted(folder.glob(f"*{PART_SUFFIX}"))
    return sorted([*folder.glob(f"{key}{KEY_SEPARATOR}part-*{PART_SUFFIX}"),
                   *folder.glob(f"part-*{PART_SUFFIX}")])


def write_part(folder: Path, name: str, table: pa.Table) -> Path:
    """Write `table` as `<folder>/<name>.parquet`, atomically; its path."""
    folder.mkdir(parents=True, exist_ok=True)
    final = folder / f"{name}{PART_SUFFIX}"
    tmp = folder / f".{name}{PART_SUFFIX}.{os.getpid()}.tmp"
    with atomic_file(final, tmp) as f:
        pq.write_table(table, f, compression="zstd")
    fsync_dir(folder)
    return final


def append_part(root: DataRoot, table: str, columns: dict[str, pa.Array], *,
                part_column: str = "part_id", key: str | None = None) -> str:
    """Write one part of `table` from `columns` (any order), keyed if its rows are all `key`'s;
    the table's last column (written_at / finished_at / scored_at) gets the time of writing and
    `part_column`, if the table has it, the part's name. ValueError if the result does not match
    the DDL. The part's path relative to the root."""
    stamp = datetime.now(UTC)
    name = part_name(stamp, key)
    schema = declared_schema(table)
    n = len(next(iter(columns.values())))
    stamp_col = schema.names[-1]
    columns = {**columns, stamp_col: pa.array([stamp] * n, schema.field(stamp_col).type)}
    if part_column in schema.names:
        columns[part_column] = pa.array([name] * n, pa.string())
    out = pa.table([columns[f.name] for f in schema], schema=schema)
    if canonical_schema(out.schema) != schema:
        raise ValueError(f"{table} part does not match the DDL:\n{out.schema}")
    return root.relative(write_part(root.table_dir(table), name, out))


def _parts_connection() -> duckdb.DuckDBPyConnection:
    """An in-memory DuckDB with the derived tables' macros `<table>_parts(files)`."""
    con = duckdb.connect()
    con.execute(parts_macros())
    return con


def read_parts(root: DataRoot, table: str, query_name: str, *, key: str | None = None,
               **params: Any) -> pa.Table:
    """`warehouse/queries/<query_name>.sql` over the parts of `table` (their paths bound to
    `$glob`, with `params`) — only those that may hold `key`'s rows if a key is given (the query
    must still select them) — or the empty declared table if there is no such part."""
    files = part_files(root.table_dir(table), key)
    if not files:
        return declared_schema(table).empty_table()
    con = connection(("parts",), _parts_connection)
    try:
        return con.sql(query(query_name), params={
            "glob": [str(f) for f in files], **params}).to_arrow_table()
    finally:
        con.close()
