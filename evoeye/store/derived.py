"""The tables later stages derive and append to: flat parts under `<root>/warehouse/<table>/`.

monitor_scores (evaluation), feedback and campaign_rounds (evolution) and attribution (explain)
are written one part per write — `part-<utc stamp>-<id>.parquet`, columns as the table's DDL
declares them (temporary file, fsync, rename: a killed write leaves no partial part) — and read
back with a query from `warehouse/queries/` whose `$glob` names the parts, every value bound.
Each table's module keeps its own key and writes under the warehouse writer lock.
"""

from __future__ import annotations

import os
import uuid
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import duckdb
import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.atomic import atomic_file, fsync_dir
from evoeye.paths import DataRoot
from evoeye.store.schema import canonical_schema, declared_schema
from evoeye.store.sqlfiles import query

PART_SUFFIX = ".parquet"


def part_name(stamp: datetime) -> str:
    """A new part's name: `part-<utc stamp>-<8 hex>`."""
    return f"part-{stamp:%Y%m%dT%H%M%SZ}-{uuid.uuid4().hex[:8]}"


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
                part_column: str = "part_id") -> str:
    """Write one part of `table` from `columns` (any order); the table's last column (written_at
    / finished_at / scored_at) gets the time of writing and `part_column`, if the table has it,
    the part's name. ValueError if the result does not match the DDL. The part's path relative
    to the root."""
    stamp = datetime.now(UTC)
    name = part_name(stamp)
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


def read_parts(root: DataRoot, table: str, query_name: str, **params: Any) -> pa.Table:
    """`warehouse/queries/<query_name>.sql` over the parts of `table` (bound to `$glob`, with
    `params`), or the empty declared table if there is no part yet."""
    folder = root.table_dir(table)
    if not any(folder.glob(f"*{PART_SUFFIX}")):
        return declared_schema(table).empty_table()
    con = duckdb.connect()
    try:
        return con.sql(query(query_name), params={
            "glob": str(folder / f"*{PART_SUFFIX}"), **params}).to_arrow_table()
    finally:
        con.close()
