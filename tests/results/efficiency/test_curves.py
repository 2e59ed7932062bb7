"""Learning curves in pool mode: paired starts, the pool's runs, determinism, resume."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.results.efficiency.acquire import PoolAcquirer
from evoeye.results.efficiency.curves import initial_rows, run_curve, training_seed
from evoeye.results.efficiency.oracle import run_oracle
from evoeye.results.efficiency.sets import concat_windows
from evoeye.results.ledger import Ledger


def test_every_strategy_starts_from_the_seeds_initial_runs_and_picks_unused_pool_runs(
        context) -> None:
    pool_ids = set(context.bank.pool.scenario_id)
    collided = context.bank.pool.collided
    init = set(context.bank.pool.scenario_id[initial_rows(collided, 6, 0)])
    assert init != set(context.bank.pool.scenario_id[initial_rows(collided, 6, 1)])
    curves = {s: run_curve(context, s, 0, PoolAcquirer(context.bank))
              for s in ("uniform", "boundary")}
    for name, curve in curves.items():
        acquired = curve["acquired_ids"]
        assert len(acquired) == len(set(acquired)) == max(context.config.checkpoints_of(name)) - 6
        assert set(acquired) <= pool_ids - init
        assert list(curve["budgets"]) == [str(b) for b in (6, *context.config.checkpoints_of(name))]
        assert curve["budgets"]["6"] == curves["uniform"]["budgets"]["6"]  # the same G_0
        assert curve["budgets"]["10"]["acquired"]["runs"] == 4
    assert set(curves["uniform"]["budgets"]) - set(curves["boundary"]["budgets"]) == {"18"}


def test_a_curve_is_deterministic_and_a_rerun_finds_it(context) -> None:
    first = run_curve(context, "evoeye", 1, PoolAcquirer(context.bank))
    found = context.ledger.found["efficiency-curve"]
    again = run_curve(context, "evoeye", 1, PoolAcquirer(context.bank))
    assert again == first and context.ledger.found["efficiency-curve"] == found + 1
    for entry in context.ledger.folder.glob("efficiency-curve-*.json"):
        entry.unlink()
    assert run_curve(context, "evoeye", 1, PoolAcquirer(context.bank)) == first


def test_retrain_trains_the_per_round_monitor_again_only_where_feedback_is_read(
        context, tmp_path, monkeypatch) -> None:
    """Under `update="retrain"` the per-round monitor is trained from scratch every round for a
    feedback reader (and is the checkpoint's monitor), and not at all for a blind strategy,
    whose picks and from-scratch figures are the replay curve's."""
    ctx = replace(context, config=replace(context.config, update="retrain", n_round=2),
                  ledger=Ledger(DataRoot.resolve(tmp_path / "fresh")))  # rounds between checkpoints
    trainings = []
    real = ctx.learner.scratch
    monkeypatch.setattr(ctx.learner, "scratch",
                        lambda train, seed, weights=None: trainings.append(seed)
                        or real(train, seed, weights))
    blind = run_curve(ctx, "uniform", 0, PoolAcquirer(ctx.bank))
    checkpoints = len(ctx.config.checkpoints_of("uniform"))
    assert len(trainings) == 1 + checkpoints  # G_0 and one per checkpoint: no per-round ones
    replayed = run_curve(context, "uniform", 0, PoolAcquirer(context.bank))
    assert blind["acquired_ids"] == replayed["acquired_ids"]
    for budget, entry in blind["budgets"].items():
        assert entry["update"] == entry["scratch"] == replayed["budgets"][budget]["scratch"]

    trainings.clear()
    reader = run_curve(ctx, "evoeye", 0, PoolAcquirer(ctx.bank))
    rounds = (max(ctx.config.checkpoints) - ctx.config.initial_runs) // 2
    assert len(trainings) == 1 + rounds  # G_0, then one a round; a checkpoint reuses its round's
    assert trainings[1:] == [training_seed(0, ctx.config.initial_runs + 2 * r)
                             for r in range(1, rounds + 1)]
    for entry in reader["budgets"].values():
        assert entry["update"] == entry["scratch"]
    assert ctx.ledger.computed["efficiency-curve"] == 2  # not found under the replay keys


def test_the_oracle_picks_by_its_set_and_keeps_its_choice(context) -> None:
    curve = run_oracle(context, 0)
    assert len(curve["kinds"]) == len(context.config.checkpoints)
    for b in context.config.checkpoints:
        entry = curve["budgets"][str(b)]
        assert entry["chosen"] in ("uniform", "error", "margin", "mixed")
        assert entry["acquired"]["runs"] == b - context.config.initial_runs
        assert set(entry["scratch"]) == {"test", "boundary"}


def test_the_oracles_control_chooses_among_uniform_draws_only_and_is_a_unit_of_its_own(
        context) -> None:
    oracle = run_oracle(context, 0)
    computed = context.ledger.computed["efficiency-curve"]
    control = run_oracle(context, 0, control=True)
    assert context.ledger.computed["efficiency-curve"] == computed + 1  # not the oracle's unit
    assert control["kinds"] == ["uniform"] * len(context.config.checkpoints)
    assert control["budgets"][str(context.config.initial_runs)] == oracle["budgets"][
        str(context.config.initial_runs)]  # the same G_0
    for b in context.config.checkpoints:
        assert control["budgets"][str(b)]["acquired"]["runs"] == b - context.config.initial_runs


def test_concatenated_windows_equal_the_pool_view(context) -> None:
    ids = list(context.bank.pool.scenario_id[:5])
    view = context.bank.data.take(ids)
    parts = [context.bank.data.take([i]) for i in ids]
    joined = concat_windows(parts)
    np.testing.assert_array_equal(joined.label, view.label)
    np.testing.assert_array_equal(joined.scenario_id, view.scenario_id)
    for name, arr in view.arrays().items():
        np.testing.assert_array_equal(joined.arrays()[name], arr, err_msg=name)


def test_an_initial_set_always_holds_a_collision_and_keeps_a_first_draw_that_has_one() -> None:
    collided = np.zeros(1000, bool)
    collided[::40] = True  # 2.5 %: a draw of 40 misses every collision about one time in three
    first = {s: np.sort(np.random.default_rng([s, 0]).choice(1000, size=40, replace=False))
             for s in range(30)}
    for seed, rows in first.items():
        init = initial_rows(collided, 40, seed)
        assert collided[init].any() and len(set(init)) == 40
        if collided[rows].any():
            np.testing.assert_array_equal(init, rows)  # unchanged where it needed no redraw
    assert any(not collided[rows].any() for rows in first.values())  # the case is exercised
    with pytest.raises(ValueError, match="no collision run"):
        initial_rows(np.zeros(100, bool), 10, 0)


def test_a_ce_is_curve_keeps_its_runs_densities_and_trains_with_their_weights(
        context, tmp_path, monkeypatch) -> None:
    weighted = replace(context.learner, params=replace(context.learner.params,
                                                       importance_weights=True))
    ctx = replace(context, learner=weighted, ledger=Ledger(DataRoot.resolve(tmp_path / "w")))
    given = []
    real = weighted.scratch
    monkeypatch.setattr(weighted, "scratch", lambda train, seed, weights=None:
                        given.append(weights) or real(train, seed, weights))
    curve = run_curve(ctx, "ce-is", 0, PoolAcquirer(ctx.bank))
    n = len(curve["acquired_ids"])
    assert len(curve["log_q"]) == len(curve["log_p"]) == n and np.isfinite(curve["log_q"]).all()
    for budget in ctx.config.checkpoints:
        rate = curve["budgets"][str(budget)]["acquired"]["failure_rate"]
        assert rate["n"] == budget - ctx.config.initial_runs and rate["method"] == "is"
    ratio = np.exp(np.array(curve["log_p"]) - np.array(curve["log_q"]))
    last = given[-1]  # the last checkpoint's monitor: every run, the acquired ones by p/q
    np.testing.assert_allclose([last[s] for s in curve["acquired_ids"]], ratio)
    assert "log_q" not in run_curve(context, "uniform", 0, PoolAcquirer(context.bank))
