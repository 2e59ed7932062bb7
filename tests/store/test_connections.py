"""Shared DuckDB connections: views installed once per warehouse state, answers as fresh ones."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.store import catalog, connections, ingest
from evoeye.store.catalog import Warehouse
from evoeye.store.connections import shared_connections
from evoeye.store.feedback import FeedbackRows, feedback_of, write_feedback

COUNT = "SELECT count(*) AS n FROM scenarios"


@pytest.fixture
def installs(monkeypatch) -> list[tuple[bool, ...]]:
    """The warehouse states views are installed for, one entry per install."""
    seen: list[tuple[bool, ...]] = []
    real = catalog.install_views

    def counting(con, root, present=None, **options):
        seen.append(present)
        return real(con, root, present, **options)

    monkeypatch.setattr(catalog, "install_views", counting)
    return seen


def count(root: DataRoot) -> int:
    return Warehouse(root).sql(COUNT).column("n")[0].as_py()


def test_views_are_installed_once_per_state_and_see_new_parts(root, add_run, installs) -> None:
    with shared_connections():
        assert count(root) == 0 and count(root) == 0  # no part yet: the declared tables
        assert len(installs) == 1
        add_run("a", seed=1)
        ingest(root)  # the tables' first parts: views of the new state
        installs.remove(None)  # the catalog file ingest rewrites
        assert count(root) == 1 and count(root) == 1
        assert len(installs) == 2 and installs[0] != installs[1]
        add_run("b", seed=2)
        ingest(root)  # a new part of tables that had parts: the same views see it
        installs.remove(None)
        assert count(root) == 2
        assert len(installs) == 2
        rows = FeedbackRows("highway-cut-in", "m1", "raw", np.array(["a"]), np.array([0.5]),
                            np.array([3]))
        write_feedback(root, rows)  # read and written through a shared bare database
        assert feedback_of(root, "m1", "raw") == {"a": 0.5}
    assert count(root) == 2 and len(installs) == 3  # outside the block: a database each time


def test_what_one_connection_registers_or_sets_stays_its_own(root, add_run, tmp_path) -> None:
    import pyarrow as pa

    add_run("a", seed=1)
    ingest(root)
    outside = tmp_path / "outside.csv"
    outside.write_text("x\n1\n")
    with shared_connections():
        first = Warehouse(root).connect()
        first.register("scenarios", pa.table({"scenario_id": ["x", "y", "z"]}))
        assert first.sql(COUNT).fetchall() == [(3,)]
        assert count(root) == 1  # another connection to the same database
        first.close()
        # a user's query locks its database down: never the shared one
        assert Warehouse(root).read_only_sql(COUNT).column(0)[0].as_py() == 1
        assert Warehouse(root).sql(f"SELECT count(*) AS n FROM read_csv('{outside}')"
                                   ).column("n")[0].as_py() == 1


def test_a_forked_child_never_uses_its_parents_database(root, add_run, installs,
                                                        monkeypatch) -> None:
    add_run("a", seed=1)
    ingest(root)
    installs.clear()
    with shared_connections():
        assert count(root) == 1 and len(installs) == 1
        monkeypatch.setattr(connections.os, "getpid", lambda: -1)  # as in a forked child
        assert count(root) == 1 and count(root) == 1
        assert len(installs) == 3


def test_connections_of_the_block_end_with_it(root, add_run) -> None:
    add_run("a", seed=1)
    ingest(root)
    with shared_connections():
        kept = Warehouse(root).connect()
    with pytest.raises(Exception, match="closed"):
        kept.sql(COUNT).fetchall()
