"""The read side of the warehouse, in SQL files: `warehouse/views/*.sql`, `warehouse/queries/*.sql`
and `warehouse/parts.sql`.

Views (and table macros) are scripts run in file-name order when a connection opens; queries are
single statements with `$name` parameters, bound by DuckDB and never formatted into the text;
`parts.sql` holds the macros that read the derived tables' parts, for the views and the queries.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from evoeye.store.schema import PARTS_SQL, QUERIES_DIR, VIEWS_DIR


@cache
def view_scripts() -> tuple[tuple[str, str], ...]:
    """(file stem, script) of every view file, in the order they must run."""
    return tuple((p.stem, p.read_text(encoding="utf-8")) for p in sorted(VIEWS_DIR.glob("*.sql")))


def query_names() -> tuple[str, ...]:
    return tuple(p.stem for p in sorted(QUERIES_DIR.glob("*.sql")))


@cache
def query(name: str) -> str:
    """The text of `warehouse/queries/<name>.sql`."""
    path: Path = QUERIES_DIR / f"{name}.sql"
    if not path.is_file():
        raise KeyError(f"no query {name!r} in {QUERIES_DIR}; known: {query_names()}")
    return path.read_text(encoding="utf-8")


@cache
def parts_macros() -> str:
    """The script defining each derived table's macro `<table>_parts(files)`."""
    return PARTS_SQL.read_text(encoding="utf-8")
