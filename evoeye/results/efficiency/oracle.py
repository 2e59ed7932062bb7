"""The oracle: a greedy chooser that knows every pool run's outcome and picks by true benefit,
so its gain over Uniform is a lower bound on what choosing runs from this pool can gain.

At each step from one budget to the next it tries `oracle_candidates` increments of the step's
size from the unused pool and keeps the one whose from-scratch monitor scores the highest
AUPRC on the oracle set (uniform runs of their own, neither the Test Set nor the pool):
* uniform draws (the reference's own kind of choice), all but three of the candidates;
* the runs the current monitor errs on most (true per-run error, on a sample of the unused
  pool scored with the step's monitor);
* near misses and collisions (true margins: every collision of the sample and the safe runs
  that passed closest, half and half);
* half of each of the last two with uniform draws.
The kept monitor is the checkpoint's: trained with the seed every strategy's checkpoint
monitor gets (an ensemble as theirs are, with `members` > 1), so it is judged on the Test and
boundary sets like theirs. The oracle's choices
use the outcomes and errors of runs before they are acquired, which no strategy can know: it
is a bound, not a strategy. It is greedy (one step at a time, one step per checkpoint) and tries
a handful of increments, so it is a lower bound of the best choice, never a ceiling: an oracle
that barely beats Uniform says this greedy search found little, not that no choice of runs can
gain more.

Its control, `oracle-uniform`, is the same greedy search with every candidate a uniform draw:
as many candidates, judged on the same set. A best-of-k choice among equally likely increments
gains on its own, from the spread of what a monitor learns from a few runs (its training is
chaotic: one run more or less changes it); the control measures that part. The oracle's gain
over its control is what choosing the *kind* of run (errors, near misses, collisions) adds.
"""

from __future__ import annotations

import numpy as np

from evoeye.evolve.campaign.assess import metrics_dict
from evoeye.results.efficiency.config import ORACLE, ORACLE_UNIFORM
from evoeye.results.efficiency.curves import (
    Context,
    acquired_summary,
    initial_rows,
    members_key,
    training_seed,
)
from evoeye.results.efficiency.learner import run_feedback

SAMPLE = 1000  # unused pool runs the error and margin candidates are chosen from


def _candidates(ctx: Context, monitor, used: np.ndarray, size: int,
                rng: np.random.Generator, control: bool) -> list[tuple[str, np.ndarray]]:
    pool = ctx.bank.pool
    free = np.flatnonzero(~used)
    if control:
        return [("uniform", rng.choice(free, size=size, replace=False))
                for _ in range(ctx.config.oracle_candidates)]
    sample = np.sort(rng.choice(free, size=min(SAMPLE, len(free)), replace=False))
    errors = run_feedback(monitor, ctx.bank.windows(pool.scenario_id[sample]))
    err = np.array([errors.get(str(s), -1.0) for s in pool.scenario_id[sample]])
    by_error = sample[np.argsort(-err, kind="stable")]
    gap = np.where(pool.collided[sample], -1.0, np.nan_to_num(pool.min_distance_m[sample],
                                                              nan=np.inf))
    by_margin = sample[np.argsort(np.abs(gap), kind="stable")]

    def uniform(k: int, exclude=()) -> np.ndarray:
        left = np.setdiff1d(free, exclude)
        return rng.choice(left, size=k, replace=False)

    half = size // 2
    out = [("uniform", uniform(size)) for _ in range(max(1, ctx.config.oracle_candidates - 3))]
    out += [("error", by_error[:size]), ("margin", by_margin[:size])]
    mixed = np.concatenate([by_error[: half - half // 2], by_margin[: half // 2]])
    mixed = np.unique(mixed)
    out.append(("mixed", np.concatenate([mixed, uniform(size - len(mixed), mixed)])))
    return out


def run_oracle(ctx: Context, seed: int, control: bool = False) -> dict:
    """The oracle's learning curve at one seed (a ledger unit); with `control`, its
    uniform-only control's (module doc)."""
    cfg = ctx.config
    name = ORACLE_UNIFORM if control else ORACLE
    inputs = {"regime": ctx.regime, "sets": ctx.fingerprint, "strategy": name, "seed": seed,
              "initial": cfg.initial_runs, "budgets": list(cfg.checkpoints),
              "candidates": cfg.oracle_candidates, "recipe": ctx.learner.recipe,
              **members_key(cfg.members)}
    return ctx.ledger.remember("efficiency-curve", inputs, lambda: _oracle(ctx, seed, name))


def _oracle(ctx: Context, seed: int, name: str) -> dict:
    cfg, pool, learner = ctx.config, ctx.bank.pool, ctx.learner
    oracle_set = ctx.bank.data.sets["oracle"]
    init = np.zeros(len(pool), bool)
    init[initial_rows(pool.collided, cfg.initial_runs, seed)] = True
    used = init.copy()
    monitor = learner.checkpoint(ctx.bank.windows(pool.scenario_id[used]),
                                 training_seed(seed, cfg.initial_runs))
    g0 = ctx.scratch_figures(pool.scenario_id[used], cfg.initial_runs, seed, monitor)
    out: dict = {"budgets": {str(cfg.initial_runs): {"scratch": g0}}, "kinds": []}
    for step, budget in enumerate(cfg.checkpoints):
        rng = np.random.default_rng([seed, 99, step])
        size = budget - int(used.sum())
        best = None
        for kind, rows in _candidates(ctx, monitor, used, size, rng, name == ORACLE_UNIFORM):
            ids = [*pool.scenario_id[used], *pool.scenario_id[rows]]
            candidate = learner.checkpoint(ctx.bank.windows(ids), training_seed(seed, budget))
            auprc = metrics_dict(candidate.score(oracle_set), oracle_set.label,
                                 candidate.thresholds)["auprc"]
            ctx.say(f"{ctx.regime}: {name} seed {seed} at {budget}: {kind} {auprc:.3f}")
            if best is None or auprc > best[0]:
                best = (auprc, kind, rows, candidate)
        auprc, kind, rows, monitor = best
        used[rows] = True
        out["kinds"].append(kind)
        acq = used & ~init
        out["budgets"][str(budget)] = {
            "scratch": learner.judge(monitor), "chosen": kind, "oracle_auprc": auprc,
            "acquired": acquired_summary(pool.collided[acq], pool.fitness[acq])}
    return out
