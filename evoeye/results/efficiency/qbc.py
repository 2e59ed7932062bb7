"""Query-by-committee on the candidates' own windows: a pool-mode diagnostic, not a strategy.

Each round a committee of K FusionMonitors, trained from scratch on every run acquired so far
(`Learner.committee`: K = the study's `members` when it is at least 2, else COMMITTEE; member
0 with the training seed every strategy's monitor at that many runs gets, the others with seeds
derived from it), scores every window of a sample of the unused pool (SAMPLE runs, drawn per
round). A candidate's disagreement is the mean over its windows of the population standard
deviation of the members' risks (`learner.run_disagreement`, the measure `disagreement`'s
committee uses): the spread, in risk units, where members that saw the same runs disagree.
The round takes the n_round candidates the committee disagrees on most (ties by pool order).
No outcome and no label is read, only the committee's scores.

It differs from the `disagreement` strategy (`evoeye.evolve.search.disagreement`), which
predicts the disagreement over θ with a forest fitted to the acquired runs' own disagreement,
because a strategy chooses θ before the run exists. Here the candidates were simulated
already, so their windows are scored directly: that is only possible on a pre-simulated pool,
hence pool mode only, and it says how much `disagreement` loses by predicting over θ.

At a checkpoint the committee's first `members` are the checkpoint's monitor (the same
monitor, with the same seeds, `Learner.checkpoint` trains for every strategy), judged like
theirs. Cost: K trainings per round instead of the per-round monitor's one update, and K
scorings of SAMPLE runs' windows.
"""

from __future__ import annotations

import numpy as np

from evoeye.results.efficiency.config import QBC
from evoeye.results.efficiency.curves import (
    Context,
    acquired_summary,
    initial_rows,
    members_key,
    training_seed,
)
from evoeye.results.efficiency.learner import run_disagreement
from evoeye.results.efficiency.oracle import SAMPLE

COMMITTEE = 3  # members when the study's checkpoint monitors have one


def committee_size(members: int) -> int:
    """K: the study's ensemble size when it has at least 2 members, else COMMITTEE."""
    return members if members >= 2 else COMMITTEE


def most_disagreed(committee, windows, candidates: np.ndarray, ids: np.ndarray,
                   n: int) -> tuple[np.ndarray, np.ndarray]:
    """(the n candidates (pool rows) with the largest disagreement, in that order; every
    candidate's disagreement, −inf for a run without windows). `ids`: the candidates' ids."""
    spread = run_disagreement(committee, windows)
    d = np.array([spread.get(str(s), -np.inf) for s in ids])
    return candidates[np.argsort(-d, kind="stable")[:n]], d


def run_qbc(ctx: Context, seed: int) -> dict:
    """The qbc curve at one seed (a ledger unit; module doc)."""
    cfg = ctx.config
    inputs = {"regime": ctx.regime, "sets": ctx.fingerprint, "strategy": QBC, "seed": seed,
              "mode": "pool", "initial": cfg.initial_runs, "budgets": list(cfg.checkpoints),
              "n_round": cfg.n_round, "recipe": ctx.learner.recipe,
              "committee": committee_size(cfg.members), "sample": SAMPLE,
              **members_key(cfg.members)}
    return ctx.ledger.remember("efficiency-curve", inputs, lambda: _qbc(ctx, seed))


def _qbc(ctx: Context, seed: int) -> dict:
    cfg, pool, learner = ctx.config, ctx.bank.pool, ctx.learner
    k = committee_size(cfg.members)
    init = initial_rows(pool.collided, cfg.initial_runs, seed)
    used = np.zeros(len(pool), bool)
    used[init] = True
    rows = list(init)

    def trained() -> tuple[list, dict | None]:
        """The committee on the runs so far (at the last checkpoint only the members its
        monitor needs), and at a checkpoint that monitor's figures."""
        n, last = len(rows), cfg.checkpoints[-1]
        ids, tseed = pool.scenario_id[rows], training_seed(seed, n)
        committee = learner.committee(ctx.bank.windows(ids), tseed,
                                      cfg.members if n == last else k)
        if n != cfg.initial_runs and n not in cfg.checkpoints:
            return committee, None
        return committee, ctx.scratch_figures(ids, n, seed,
                                              learner.as_checkpoint(committee, tseed))

    committee, g0 = trained()
    out: dict = {"budgets": {str(cfg.initial_runs): {"scratch": g0}}, "disagreement": []}
    round_ = 0
    while len(rows) < cfg.checkpoints[-1]:
        round_ += 1
        free = np.flatnonzero(~used)
        rng = np.random.default_rng([seed, 77, round_])
        sample = np.sort(rng.choice(free, size=min(SAMPLE, len(free)), replace=False))
        ids = pool.scenario_id[sample]
        picks, d = most_disagreed(committee, ctx.bank.windows(ids), sample, ids, cfg.n_round)
        top = np.sort(d[np.isfinite(d)])[::-1]
        out["disagreement"].append({"picked": float(np.mean(top[: cfg.n_round])),
                                    "sample": float(np.mean(top))})
        used[picks] = True
        rows += list(picks)
        ctx.say(f"{ctx.regime}: {QBC} seed {seed} at {len(rows)} runs")
        committee, figures = trained()
        if figures is not None:
            acq = np.array(rows[cfg.initial_runs:])
            out["budgets"][str(len(rows))] = {
                "scratch": figures,
                "acquired": acquired_summary(pool.collided[acq], pool.fitness[acq])}
    out["acquired_ids"] = [str(s) for s in pool.scenario_id[rows[cfg.initial_runs:]]]
    out["kinds"] = [QBC] * (len(rows) - cfg.initial_runs)
    return out
