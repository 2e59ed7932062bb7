"""A tiny data root for `evoeye results`: synthetic runs that are sure to hold collisions.

Random frames from `evoeye.log.synthetic`, through the real log and ingest layers: an initial
batch `init` of 16 runs and a held-out Test Set batch `held` of 8, every other run colliding at
frame 80 of 100, so every split holds unsafe and safe frames whatever the simulator does.
Campaigns add real simulated runs to it; the tables need no collision among those.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from evoeye.log.synthetic import write_synthetic_batch
from evoeye.paths import DataRoot
from evoeye.store import ingest


def build_root(path: Path) -> DataRoot:
    """The synthetic initial and held-out batches, ingested."""
    root = DataRoot.resolve(path)
    write_synthetic_batch(root, "init", 16)
    write_synthetic_batch(root, "held", 8, first_seed=100)
    ingest(root)
    return root


@pytest.fixture(scope="session")
def results_root_builder():
    """build_root, for tests that need a root of their own."""
    return build_root
