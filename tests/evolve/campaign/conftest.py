"""A seeded data root for campaigns, and private copies of it."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from campaign_helpers import SCENARIO, SPLITS

from evoeye.batch import plan_uniform, run_batch
from evoeye.paths import DataRoot
from evoeye.store import ingest


@pytest.fixture(scope="session")
def seeded(tmp_path_factory: pytest.TempPathFactory) -> tuple[DataRoot, str]:
    """(root, G_0): 16 ingested runs and a G_0 trained for one epoch, shared by the tests of
    this folder (campaigns run on a `root_copy`)."""
    from evoeye.monitor import train_monitor

    data = DataRoot.resolve(tmp_path_factory.mktemp("seeded") / "data")
    run_batch(plan_uniform(SCENARIO, 16, 6), data)  # seed 6: both classes in every split
    ingest(data)
    return data, train_monitor(data, SCENARIO, seed=0, splits=SPLITS, epochs=1)


@pytest.fixture
def root_copy(seeded, tmp_path: Path) -> Callable[[str], DataRoot]:
    """A private copy of the seeded root, so each test's campaign starts from the same data."""
    def make(name: str) -> DataRoot:
        dst = tmp_path / name
        shutil.copytree(seeded[0].path, dst)
        return DataRoot.resolve(dst)
    return make
