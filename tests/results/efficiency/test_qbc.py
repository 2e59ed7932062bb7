"""Query-by-committee on the unused pool runs' own windows (pool mode only)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from evoeye.paths import DataRoot
from evoeye.results.efficiency.acquire import PoolAcquirer
from evoeye.results.efficiency.curves import initial_rows, run_curve, training_seed
from evoeye.results.efficiency.oracle import SAMPLE
from evoeye.results.efficiency.qbc import committee_size, most_disagreed, run_qbc
from evoeye.results.ledger import Ledger


class _Member:
    """A committee member whose risk on a run's windows is set per run."""

    def __init__(self, risk: dict[str, float]) -> None:
        self.risk = risk

    def score(self, windows) -> np.ndarray:
        return np.array([self.risk[str(s)] for s in windows.scenario_id], np.float32)


def test_the_most_disagreed_candidates_come_first(context) -> None:
    pool = context.bank.pool
    rows = np.arange(4)
    ids = pool.scenario_id[rows]
    # members' risks per run: run 2 spread widest, run 0 next, runs 1 and 3 agree
    risks = [(0.2, 0.5, 0.1, 0.7), (0.4, 0.5, 0.9, 0.7), (0.6, 0.5, 0.5, 0.7)]
    committee = [_Member(dict(zip(map(str, ids), r, strict=True))) for r in risks]
    picks, spread = most_disagreed(committee, context.bank.windows(ids), rows, ids, 2)
    assert list(picks) == [2, 0]
    expected = [np.std([r[i] for r in risks]) for i in range(4)]  # population SD per run
    np.testing.assert_allclose(spread, expected, rtol=1e-6, atol=1e-7)


def test_a_qbc_curve_takes_what_its_committee_disagrees_on_most(context) -> None:
    cfg, pool, learner = context.config, context.bank.pool, context.learner
    curve = run_qbc(context, 0)
    uniform = run_curve(context, "uniform", 0, PoolAcquirer(context.bank))
    init = initial_rows(pool.collided, cfg.initial_runs, 0)
    acquired = curve["acquired_ids"]
    assert len(acquired) == len(set(acquired)) == cfg.checkpoints[-1] - cfg.initial_runs
    assert not set(acquired) & set(pool.scenario_id[init])
    assert list(curve["budgets"]) == [str(b) for b in (cfg.initial_runs, *cfg.checkpoints)]
    g0 = str(cfg.initial_runs)
    assert curve["budgets"][g0]["scratch"] == uniform["budgets"][g0]["scratch"]  # same G_0

    # round 1 again, independently: the committee on D_init scores its sample of the pool
    k = committee_size(cfg.members)
    committee = learner.committee(context.bank.windows(pool.scenario_id[init]),
                                  training_seed(0, cfg.initial_runs), k)
    used = np.zeros(len(pool), bool)
    used[init] = True
    free = np.flatnonzero(~used)
    sample = np.sort(np.random.default_rng([0, 77, 1]).choice(
        free, size=min(SAMPLE, len(free)), replace=False))
    ids = pool.scenario_id[sample]
    picks, spread = most_disagreed(committee, context.bank.windows(ids), sample, ids,
                                   cfg.n_round)
    assert acquired[: cfg.n_round] == [str(s) for s in pool.scenario_id[picks]]
    taken = spread[np.isin(sample, picks)]
    assert taken.min() >= spread[~np.isin(sample, picks)].max()  # none left more disputed
    assert curve["disagreement"][0]["picked"] >= curve["disagreement"][0]["sample"]


def test_the_committee_is_the_study_ensemble_or_three() -> None:
    assert committee_size(1) == 3 and committee_size(2) == 2 and committee_size(5) == 5


def test_with_an_ensemble_the_committee_is_the_checkpoints_ensemble(context, tmp_path) -> None:
    """members = 2: the committee has two members, and its checkpoint monitor is the very
    ensemble every strategy's checkpoint gets (the same G_0 figures as Uniform's)."""
    ctx = replace(context, config=replace(context.config, members=2, checkpoints=(10,)),
                  learner=replace(context.learner, members=2),
                  ledger=Ledger(DataRoot.resolve(tmp_path / "k2")))
    curve = run_qbc(ctx, 0)
    single = run_qbc(replace(context, config=replace(context.config, checkpoints=(10,))), 0)
    assert curve["budgets"]["6"] != single["budgets"]["6"]  # an ensemble, not one monitor
    apart = replace(ctx, ledger=Ledger(DataRoot.resolve(tmp_path / "apart")))  # trained again
    uniform = run_curve(apart, "uniform", 0, PoolAcquirer(ctx.bank))
    assert curve["budgets"]["6"]["scratch"] == uniform["budgets"]["6"]["scratch"]
