"""One Prefect test server for the whole session (it takes ~15-20 s to start).

PREFECT_HOME points at a temporary folder so tests never touch the user's Prefect profile.
Every test under tests/flows is put in one xdist group, so `-n 2 --dist loadgroup` starts
the server in one worker only.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

os.environ["PREFECT_HOME"] = tempfile.mkdtemp(prefix="evoeye-prefect-")

FLOWS_DIR = Path(__file__).resolve().parent


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if FLOWS_DIR in Path(str(item.fspath)).resolve().parents:
            item.add_marker(pytest.mark.xdist_group("prefect"))


@pytest.fixture(scope="session")
def prefect_server() -> Iterator[None]:
    """The Prefect test harness (temporary database and API server) for this session."""
    from prefect.testing.utilities import prefect_test_harness

    with prefect_test_harness(server_startup_timeout=120):
        yield
