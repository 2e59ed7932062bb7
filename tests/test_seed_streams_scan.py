"""The seed-stream scan (experiments/seed_streams.py), small: no run id occurs twice."""

from __future__ import annotations

from evoeye.evolve.search.registry import STRATEGIES
from experiments.seed_streams import scan


def test_batches_test_set_and_every_strategys_campaigns_share_no_run() -> None:
    new = scan("unprotected-intersection", 150, 30, [0, 1], 6)
    assert new["runs"] == 150 + 30 + len(STRATEGIES) * 2 * 6
    assert new["repeated"] == 0, new["where"]


def test_the_scan_finds_the_old_streams_meeting() -> None:
    where = scan("unprotected-intersection", 150, 0, [0], 2, old=True)["where"].values()
    for strategy in ("uniform-s0", "avfuzzer-s0"):  # proposal 0 was the batch's run 0
        assert any({"uniform-seed0", strategy} <= set(names) for names in where), strategy
