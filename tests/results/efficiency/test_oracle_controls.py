"""The oracle's controls and its steps: the best-of-k-training-seeds control keeps the best of
its candidates on Uniform's own runs, and the oracle steps per checkpoint (its keys as they
always were) or per round."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from evoeye.paths import DataRoot
from evoeye.results.efficiency.acquire import PoolAcquirer
from evoeye.results.efficiency.curves import blind_picks, run_curve, training_seed
from evoeye.results.efficiency.oracle import (
    SEED_STRIDE,
    oracle_auprc,
    run_oracle,
    run_seeds_control,
    steps,
)
from evoeye.results.ledger import Ledger


def _fresh(context, tmp_path, name: str, **config):
    return replace(context, config=replace(context.config, **config),
                   ledger=Ledger(DataRoot.resolve(tmp_path / name)))


def test_blind_picks_are_the_runs_uniforms_curve_acquires(context) -> None:
    curve = run_curve(context, "uniform", 0, PoolAcquirer(context.bank))
    picks = blind_picks(context, "uniform", 0, 14)
    init = context.config.initial_runs
    assert list(picks[init:]) == curve["acquired_ids"][: 14 - init]
    assert list(blind_picks(context, "uniform", 0, 10)) == list(picks[:10])


def test_the_seeds_control_keeps_its_best_training_seed_on_uniforms_runs(context) -> None:
    control = run_seeds_control(context, 1)
    uniform = run_curve(context, "uniform", 1, PoolAcquirer(context.bank))
    cfg, learner = context.config, context.learner
    g0 = uniform["budgets"][str(cfg.initial_runs)]["scratch"]
    assert control["budgets"][str(cfg.initial_runs)] == {"scratch": g0}  # the same G_0
    picks = blind_picks(context, "uniform", 1, cfg.checkpoints[-1])
    for budget in cfg.checkpoints:
        entry = control["budgets"][str(budget)]
        assert entry["acquired"] == uniform["budgets"][str(budget)]["acquired"]  # its runs
        # every candidate again, independently: seed j is the checkpoint's + j strides
        train, tseed = context.bank.windows(picks[:budget]), training_seed(1, budget)
        monitors = [learner.checkpoint(train, tseed + j * SEED_STRIDE)
                    for j in range(cfg.oracle_candidates)]
        auprcs = [oracle_auprc(context, m) for m in monitors]
        assert entry["candidates_auprc"] == auprcs
        best = int(np.argmax(auprcs))
        assert entry["chosen"] == f"seed-{best}" and entry["oracle_auprc"] == max(auprcs)
        assert entry["scratch"] == learner.judge(monitors[best])
        # candidate 0 is Uniform's own checkpoint monitor
        assert learner.judge(monitors[0]) == uniform["budgets"][str(budget)]["scratch"]


def test_the_seeds_control_is_a_unit_of_its_own(context, tmp_path) -> None:
    ctx = _fresh(context, tmp_path, "seeds", checkpoints=(10,), oracle_candidates=4)
    first = run_seeds_control(ctx, 0)
    assert ctx.ledger.computed["efficiency-curve"] == 1
    assert run_seeds_control(ctx, 0) == first and ctx.ledger.found["efficiency-curve"] == 1
    run_oracle(ctx, 0, control=True)
    assert ctx.ledger.computed["efficiency-curve"] == 2  # not the uniform-only control's


def _keys(ctx, monkeypatch) -> list[dict]:
    """The inputs of every curve unit asked for."""
    asked, real = [], ctx.ledger.remember

    def remember(kind, inputs, compute):
        if kind == "efficiency-curve":
            asked.append(dict(inputs))
        return real(kind, inputs, compute)

    monkeypatch.setattr(ctx.ledger, "remember", remember)
    return asked


def test_checkpoint_steps_keep_the_oracles_keys_and_round_steps_are_keyed_apart(
        context, tmp_path, monkeypatch) -> None:
    ctx = _fresh(context, tmp_path, "steps", checkpoints=(10, 14), oracle_candidates=4)
    asked = _keys(ctx, monkeypatch)
    by_checkpoint = run_oracle(ctx, 0)
    assert set(asked[-1]) == {"regime", "sets", "strategy", "seed", "initial", "budgets",
                              "candidates", "recipe"}  # as recorded studies' units were
    assert len(by_checkpoint["kinds"]) == 2

    rounds = replace(ctx, config=replace(ctx.config, n_round=2, oracle_step="round"))
    assert steps(rounds.config) == [8, 10, 12, 14] and steps(ctx.config) == [10, 14]
    by_round = run_oracle(rounds, 0)
    assert asked[-1]["step"] == "round" and asked[-1]["n_round"] == 2
    assert ctx.ledger.computed["efficiency-curve"] == 2  # not the checkpoint oracle's unit
    assert len(by_round["kinds"]) == 4  # one choice per round
    assert list(by_round["budgets"]) == ["6", "10", "14"]  # judged at the checkpoints only
    for b in (10, 14):
        assert by_round["budgets"][str(b)]["acquired"]["runs"] == b - 6
    assert by_round["budgets"]["6"] == by_checkpoint["budgets"]["6"]  # the same G_0
