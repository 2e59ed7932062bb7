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

from evoeye.batch import plan_uniform, run_batch
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, ingest

os.environ["PREFECT_HOME"] = tempfile.mkdtemp(prefix="evoeye-prefect-")

SCENARIO = "unprotected-intersection"  # of the `seeded` data root
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)
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


@pytest.fixture(scope="session")
def seeded(tmp_path_factory: pytest.TempPathFactory) -> tuple[DataRoot, str]:
    """A data root with 16 ingested intersection runs and a G_0 (campaign tests add to it)."""
    from evoeye.monitor import train_monitor

    root = DataRoot.resolve(tmp_path_factory.mktemp("evolve-flow") / "data")
    run_batch(plan_uniform(SCENARIO, 16, 3), root)
    ingest(root)
    return root, train_monitor(root, SCENARIO, seed=0, splits=SPLITS, epochs=1)
