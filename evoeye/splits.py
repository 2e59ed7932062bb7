"""How round-0 runs are split into train / val / test: the spec the warehouse's split macro takes.

The split itself is made in SQL (macro `scenario_splits`, warehouse/views/06_splits.sql); this is
its parameters, plain data with no dependency, so the command line and a campaign's options can
name it without loading the warehouse.
"""

from __future__ import annotations

from dataclasses import dataclass

from evoeye.paths import check_batch_name

SPLITS = ("train", "val", "test")


@dataclass(frozen=True)
class SplitSpec:
    """A scenario-level split (macro `scenario_splits`): seed, the train / val shares and an
    optional held-out test batch.

    The defaults follow the paper's datasets: half the initial data trains, the other half is
    held out and split val : test = 1 : 3. Runs of rounds >= 1 always train.

    `test_batch` names a round-0 batch simulated apart (its own seed) as a fixed Test Set: its
    runs are always 'test', never train or val; the other round-0 runs split by the shares as
    before, so with train_frac + val_frac = 1 the Test Set is that batch alone.
    """

    seed: int = 0
    train_frac: float = 0.5
    val_frac: float = 0.125
    test_batch: str | None = None

    def __post_init__(self) -> None:
        fracs_ok = min(self.train_frac, self.val_frac) >= 0.0
        if not (fracs_ok and self.train_frac + self.val_frac <= 1.0):
            raise ValueError(f"need 0 <= train_frac, val_frac and a sum <= 1: {self}")
        if self.test_batch is not None:
            check_batch_name(self.test_batch)
