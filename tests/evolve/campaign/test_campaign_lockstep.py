"""A campaign simulates the proposals that wait on no outcome together (the lockstep engine),
and acquires exactly what it acquires one run at a time: the same rounds, logs and feedback."""

from __future__ import annotations

import pytest
from campaign_helpers import config, snapshot

from evoeye.evolve.campaign import loop as campaign_mod
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.search.avfuzzer import AVFuzzer
from evoeye.evolve.search.strategies import BatchedStrategy, CountedStrategy


def _campaign(root, g0, strategy, monkeypatch):
    """Two rounds of four runs; the sizes of the groups of runs simulated together."""
    real, sizes = campaign_mod.simulate_and_keep_all, []

    def counted(specs, where):
        sizes.append(len(specs))
        return real(specs, where)

    monkeypatch.setattr(campaign_mod, "simulate_and_keep_all", counted)
    c = Campaign(root, config(g0, strategy=strategy, n_round=4))
    c.run(max_rounds=2)
    logs = sorted((root.runs / c.config.scenario / c.campaign_id).glob("*.mcap"))
    return {**snapshot(root, c), "bytes": [p.read_bytes() for p in logs]}, sizes


@pytest.mark.parametrize("strategy", ["uniform", "boundary", "avfuzzer"])
def test_runs_simulated_together_are_the_runs_simulated_one_at_a_time(
        root_copy, seeded, monkeypatch, strategy: str) -> None:
    together, sizes = _campaign(root_copy("together"), seeded[1], strategy, monkeypatch)
    assert max(sizes) > 1 and sum(sizes) == 8  # the engine stepped several runs at once

    def one(self, records, n):
        return [self.propose(records)]

    for cls in (CountedStrategy, BatchedStrategy, AVFuzzer):
        monkeypatch.setattr(cls, "propose_ahead", one)
    alone, sizes = _campaign(root_copy("alone"), seeded[1], strategy, monkeypatch)
    assert sizes == [1] * 8
    assert together == alone
    assert len(together["logs"]) == len(together["bytes"]) == 8
