"""DuckDB connections shared within a block: one database per warehouse state, opened once.

Every warehouse read opens an in-memory DuckDB and installs the views on it (`Warehouse.connect`,
≈ 60 ms: the database ≈ 15 ms, binding the view scripts most of the rest), and every derived
table read opens a bare one (≈ 15 ms). A campaign reads the warehouse about ten times a round.
Inside `shared_connections()`, `connection(key, make)` makes each database once, by `key`
(what it holds: for the views, the data root and which tables have parts, see
`evoeye.store.catalog`), and hands out cursors of it: connections of their own to the same
database (a relation one registers or a setting one changes stays its own), which read the
Parquet parts as they are at each query, as a new database would. The databases are closed
when the block ends.

Only the thread and process that entered the block share: other threads start outside it
(a context variable), and a forked child, whose copy of a parent's database must not be used,
gets a new connection every time.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Hashable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

import duckdb


class _Databases:
    """The databases of one `shared_connections()` block, by key."""

    def __init__(self) -> None:
        self.pid = os.getpid()
        self.by_key: dict[Hashable, duckdb.DuckDBPyConnection] = {}
        self.lock = threading.Lock()

    def cursor(self, key: Hashable,
               make: Callable[[], duckdb.DuckDBPyConnection]) -> duckdb.DuckDBPyConnection:
        with self.lock:
            if key not in self.by_key:
                self.by_key[key] = make()
            return self.by_key[key].cursor()

    def close(self) -> None:
        with self.lock:
            for database in self.by_key.values():
                database.close()
            self.by_key.clear()


_SHARED: ContextVar[_Databases | None] = ContextVar("evoeye_duckdb_databases", default=None)


@contextmanager
def shared_connections() -> Iterator[None]:
    """Within the block, `connection` makes each database once (module doc)."""
    databases = _Databases()
    token = _SHARED.set(databases)
    try:
        yield
    finally:
        _SHARED.reset(token)
        databases.close()


def connection(key: Hashable,
               make: Callable[[], duckdb.DuckDBPyConnection]) -> duckdb.DuckDBPyConnection:
    """`make()`, or inside `shared_connections()` a cursor of the block's database for `key`
    (made by `make` the first time). The caller closes what it gets."""
    databases = _SHARED.get()
    if databases is None or databases.pid != os.getpid():
        return make()
    return databases.cursor(key, make)
