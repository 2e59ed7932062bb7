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


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if not config.pluginmanager.hasplugin("xdist"):  # `-p no:xdist`: no groups to form
        return
    for item in items:
        if FLOWS_DIR in Path(str(item.fspath)).resolve().parents:
            item.add_marker(pytest.mark.xdist_group("prefect"))


@pytest.fixture(scope="session")
def prefect_server() -> Iterator[None]:
    """The Prefect test harness (temporary database and API server) for this session."""
    from prefect.testing.utilities import prefect_test_harness

    with prefect_test_harness(server_startup_timeout=120):
        yield


def tiny_root(path: Path) -> tuple[DataRoot, str]:
    """A data root at `path` with 16 ingested intersection runs and a G_0 (≈ 10 s)."""
    from evoeye.monitor import train_monitor

    root = DataRoot.resolve(path)
    run_batch(plan_uniform(SCENARIO, 16, 3), root)
    ingest(root)
    return root, train_monitor(root, SCENARIO, seed=0, splits=SPLITS, epochs=1)


@pytest.fixture(scope="session")
def seeded(tmp_path_factory: pytest.TempPathFactory) -> tuple[DataRoot, str]:
    """A data root with 16 ingested intersection runs and a G_0 (campaign tests add to it)."""
    return tiny_root(tmp_path_factory.mktemp("evolve-flow") / "data")


@pytest.fixture
def fresh_root(tmp_path: Path) -> tuple[DataRoot, str]:
    """A data root of the test's own, as `seeded`'s, for tests that must not share one."""
    return tiny_root(tmp_path / "data")


def _latest_artifact(key: str) -> str:
    """The Markdown of the newest artifact `key` on the test server."""
    from prefect.client.orchestration import get_client

    with get_client(sync_client=True) as client:
        found = [a for a in client.read_artifacts() if a.key == key]
    assert found, f"no artifact {key!r}"
    return max(found, key=lambda a: a.created).data


def _flow_run_names(*names: str) -> list[str]:
    """The names of the flow runs on the test server called one of `names`."""
    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import FlowRunFilter, FlowRunFilterName

    with get_client(sync_client=True) as client:
        runs = client.read_flow_runs(flow_run_filter=FlowRunFilter(
            name=FlowRunFilterName(any_=list(names))))
    return sorted(r.name for r in runs)


@pytest.fixture
def latest_artifact(prefect_server):
    """`latest_artifact(key)`: the Markdown of the newest artifact `key`."""
    return _latest_artifact


@pytest.fixture
def flow_run_names(prefect_server):
    """`flow_run_names(*names)`: the flow runs called one of `names`, sorted."""
    return _flow_run_names
