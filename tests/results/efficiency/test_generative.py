"""Generative curves: a strategy's proposals are simulated under the regime's profile, kept
as logs, and read back instead of simulated again when the curve is re-run."""

from __future__ import annotations

from dataclasses import replace

import pytest

from evoeye import batch
from evoeye.log import read_run
from evoeye.results.efficiency.acquire import SimAcquirer
from evoeye.results.efficiency.curves import run_curve


def test_a_generative_curve_simulates_its_proposals_once(context, monkeypatch) -> None:
    ctx = replace(context, config=replace(context.config, checkpoints=(10,),
                                          reference_checkpoints=(), mode="generative"))
    regime_root = ctx.bank.data.data
    curve = run_curve(ctx, "sobol", 0, SimAcquirer(ctx.bank, ctx.regime, "sobol", 5, 3.0))
    logs = sorted((regime_root.runs / "highway-cut-in" / "gen-sobol-seed0").glob("*.mcap"))
    assert sorted(p.stem for p in logs) == sorted(curve["acquired_ids"])
    assert len(logs) == 4 and all(read_run(p, topics=()).metadata["source"] == "sobol"
                                  for p in logs)

    for entry in ctx.ledger.folder.glob("efficiency-curve-*.json"):
        entry.unlink()  # the curve is computed again, from the logs on disk

    def no_simulation(specs, *args, **kwargs):
        for spec in specs:
            raise AssertionError(f"{spec.scenario_id} simulated again")
        return iter(())

    monkeypatch.setattr(batch, "run_indexed", no_simulation)
    ctx.bank.extra.clear()
    again = run_curve(ctx, "sobol", 0, SimAcquirer(ctx.bank, ctx.regime, "sobol", 5, 3.0))
    assert again == curve


def test_a_pool_proposal_without_a_row_is_refused(context) -> None:
    from evoeye.evolve.search.protocol import Proposal
    from evoeye.results.efficiency.acquire import PoolAcquirer

    with pytest.raises(ValueError, match="names no pool row"):
        PoolAcquirer(context.bank).acquire(Proposal(x=context.bank.pool.params[0],
                                                    kind="uniform"), 0, 0)
