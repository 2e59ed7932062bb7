"""A data root to supervise: eval_root's synthetic warehouse (its validation split calibrates
the triggers) and a held-out batch of four real highway runs, two of them colliding."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from evoeye.batch import plan_uniform, run_batch
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec

SCENARIO = "highway-cut-in"
BATCH = "sup"
BATCH_SEED = 5  # runs 1 and 2 of its four collide
SPLITS = SplitSpec(seed=0, train_frac=0.3, val_frac=0.3, test_batch=BATCH)
FPRS = (0.05, 0.01, 0.001)


@dataclass(frozen=True)
class Supervised:
    """The data root, and what a supervision of its batch is given."""

    root: DataRoot
    scenario: str = SCENARIO
    batch: str = BATCH
    splits: SplitSpec = SPLITS
    fprs: tuple[float, ...] = FPRS
    batch_seed: int = BATCH_SEED


@pytest.fixture(scope="session")
def sup(new_eval_root) -> Supervised:
    root = new_eval_root()
    summary = run_batch(plan_uniform(SCENARIO, 4, BATCH_SEED, batch=BATCH), root)
    assert summary.collisions == 2 and summary.failures == 0
    return Supervised(root)
