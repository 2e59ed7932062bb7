"""A Test Set that holds enough failures where they are rare: the Test stream drawn on,
outcome first, and weighted back to the scenario distribution.

At ≈ 0.1 % a uniform Test Set with 50 collisions is ≈ 31 000 runs: ≈ 40 GB of logs, and ≈ 11 M
windows to score per monitor. So past its `test_runs` the Test batch's own stream
(`plan_uniform` with its seed; a longer plan begins with the shorter one) is drawn on in chunks
of `CHUNK` runs (or `test_runs`, if fewer; batch `test-more-seed<its seed>`) that are simulated
for their outcome and logged only where they collide (`run_batch(collisions_only=True)`), until
the stream holds
`want` colliding runs or `max_runs` runs. The Test Set is then a sample of that whole stream
stratified by outcome:

* every colliding run of the stream (the batch's and the further ones), each window weight 1;
* the batch's runs that did not collide, each window weighing (the stream's safe runs) / (the
  batch's safe runs), as it stands for that many.

Every count and area on it (`frame_metrics`' `weight`) is then the one of the whole stream's
windows in expectation: unbiased for each threshold's counts, and consistent for AUPRC and AUROC
(ratios of them). Runs that failed to simulate are in neither stratum. The chunks drawn, with
their colliding runs in stream order, are kept in `test-draw.json` (`efficiency.stream`): a
re-run draws only what is missing, and the set is the same whatever was simulated before.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from evoeye.batch import BatchSummary
from evoeye.paths import DataRoot
from evoeye.results.efficiency.stream import collisions, draw_on
from evoeye.sim.episode import STATUS_OK

TEST_DRAW_FILE = "test-draw.json"
CHUNK = 1000  # further runs per chunk: what a killed draw may have to simulate again
Say = Callable[[str], None]


@dataclass(frozen=True)
class TestDraw:
    """The Test stream as far as it was used (module doc)."""

    runs: int  # the stream's runs: the batch's and the further ones used
    batch_ok: int  # the batch's runs that simulated (status ok)
    batch_collided: int  # ... and collided
    further_ok: int  # the further runs used that simulated
    further: tuple[str, ...]  # the further runs that collided, in stream order

    @property
    def collisions(self) -> int:
        return self.batch_collided + len(self.further)

    @property
    def safe_weight(self) -> float:
        """What one safe run of the batch stands for: the stream's safe runs over the batch's."""
        batch_safe = self.batch_ok - self.batch_collided
        stream_safe = batch_safe + self.further_ok - len(self.further)
        return stream_safe / batch_safe if batch_safe else 1.0

    def to_dict(self) -> dict:
        """The stream's runs and collisions, the further collisions, the safe runs' weight."""
        return {"stream_runs": self.runs, "stream_collisions": self.collisions,
                "further_collisions": len(self.further), "safe_weight": self.safe_weight}


def more_batch(seed: int) -> str:
    return f"test-more-seed{seed}"


def draw_test_failures(data: DataRoot, regime: str, seed: int, base: BatchSummary, want: int,
                       max_runs: int, *, workers: int = 1, say: Say | None = None) -> TestDraw:
    """Draw the stream of the Test batch of `seed` (`base`: its runs, simulated) on until it
    holds `want` collisions or `max_runs` runs (module doc); the draw."""
    n = base.runs
    size = min(CHUNK, n)
    used = draw_on(data, regime, seed, n, size, more_batch(seed), data.path / TEST_DRAW_FILE,
                   want, max(0, -(-(max_runs - n) // size)), held=base.collisions,
                   workers=workers, say=say)
    return TestDraw(n + len(used) * size, base.count(lambda r: r.status == STATUS_OK),
                    base.collisions, sum(c["ok"] for c in used), tuple(collisions(used)))
