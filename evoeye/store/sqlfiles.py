"""The read side of the warehouse, in SQL files: `warehouse/views/*.sql`, `warehouse/queries/*.sql`.

Views (and table macros) are scripts run in file-name order when a connection opens; queries are
single statements with `$name` parameters, bound by DuckDB and never formatted into the text.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from evoeye.store.schema import QUERIES_DIR, VIEWS_DIR


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
