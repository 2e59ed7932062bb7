"""The oracle: a greedy chooser that knows every pool run's outcome and picks by true benefit,
so its gain over Uniform is a lower bound on what choosing runs from this pool can gain.

At each step it tries `oracle_candidates` increments of the step's size from the unused pool
and keeps the one whose from-scratch monitor scores the highest AUPRC on the oracle set
(uniform runs of their own, neither the Test Set nor the pool):
* uniform draws (the reference's own kind of choice), all but three of the candidates;
* the runs the current monitor errs on most (true per-run error, on a sample of the unused
  pool scored with the step's monitor);
* near misses and collisions (true margins: every collision of the sample and the safe runs
  that passed closest, half and half);
* half of each of the last two with uniform draws.
A step goes from one checkpoint to the next (`oracle_step="checkpoint"`, the default: three
steps from 40 to 320 runs), or from one round of `n_round` runs to the next
(`oracle_step="round"`: 14 steps, each adapting to the monitor the last one kept, at 4.7× the
trainings). A candidate's monitor is trained with the seed every strategy's monitor at that
many runs gets (an ensemble as theirs are, with `members` > 1), so the monitor kept at a
checkpoint is judged on the Test and boundary sets like theirs. The oracle's choices use the
outcomes and errors of runs before they are acquired, which no strategy can know: it is a
bound, not a strategy. It is greedy (one step at a time) and tries a handful of increments, so
it is a lower bound of the best choice, never a ceiling: an oracle that barely beats Uniform
says this greedy search found little, not that no choice of runs can gain more.

Its two controls:
* `oracle-uniform`, the same greedy search with every candidate a uniform draw: as many
  candidates, judged on the same set. A best-of-k choice among equally likely increments gains
  on its own, from the spread of what a monitor learns from a few runs (its training is
  chaotic: one run more or less changes it). Keeping the best also keeps collision-richer
  increments, so it absorbs part of the kind's effect.
* `oracle-seeds`, no choice of runs at all: at each checkpoint it takes Uniform's own runs at
  that seed (`curves.blind_picks`: the very increments Uniform's curve acquires), trains
  `oracle_candidates` monitors on them from scratch — candidate 0 with the checkpoint's training
  seed (Uniform's own monitor), candidate j with that seed + j · SEED_STRIDE — and keeps the one
  that scores best on the oracle set. Its gain over Uniform is what picking the luckiest training
  seed alone gains; the oracle's gain over it is what choosing runs adds.
"""

from __future__ import annotations

import numpy as np

from evoeye.evolve.campaign.assess import metrics_dict
from evoeye.results.efficiency.config import ORACLE, ORACLE_SEEDS, ORACLE_UNIFORM
from evoeye.results.efficiency.curves import (
    Context,
    acquired_summary,
    blind_picks,
    initial_rows,
    members_key,
    training_seed,
)
from evoeye.results.efficiency.learner import run_feedback

SAMPLE = 1000  # unused pool runs the error and margin candidates (and qbc's) are chosen from
SEED_STRIDE = 7_000_003  # between the training seeds of the seeds control's candidates


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
    out = [("uniform", uniform(size)) for _ in range(ctx.config.oracle_candidates - 3)]
    out += [("error", by_error[:size]), ("margin", by_margin[:size])]
    mixed = np.concatenate([by_error[: half - half // 2], by_margin[: half // 2]])
    mixed = np.unique(mixed)
    out.append(("mixed", np.concatenate([mixed, uniform(size - len(mixed), mixed)])))
    return out


def oracle_auprc(ctx: Context, monitor) -> float:
    """The monitor's AUPRC on the oracle set, what the oracle and its controls choose by."""
    oracle_set = ctx.bank.data.sets["oracle"]
    return metrics_dict(monitor.score(oracle_set), oracle_set.label,
                        monitor.thresholds)["auprc"]


def _key(ctx: Context, name: str, seed: int) -> dict:
    cfg = ctx.config
    return {"regime": ctx.regime, "sets": ctx.fingerprint, "strategy": name, "seed": seed,
            "initial": cfg.initial_runs, "budgets": list(cfg.checkpoints),
            "candidates": cfg.oracle_candidates, "recipe": ctx.learner.recipe,
            **members_key(cfg.members)}


def run_oracle(ctx: Context, seed: int, control: bool = False) -> dict:
    """The oracle's learning curve at one seed (a ledger unit); with `control`, its
    uniform-only control's (module doc)."""
    cfg = ctx.config
    name = ORACLE_UNIFORM if control else ORACLE
    inputs = _key(ctx, name, seed)
    if cfg.oracle_step != "checkpoint":  # checkpoint steps keep the keys they were ledgered under
        inputs.update(step=cfg.oracle_step, n_round=cfg.n_round)
    return ctx.ledger.remember("efficiency-curve", inputs, lambda: _oracle(ctx, seed, name))


def steps(cfg) -> list[int]:
    """The budgets the oracle chooses an increment for (module doc): the checkpoints, or every
    round up to the last checkpoint."""
    if cfg.oracle_step == "checkpoint":
        return list(cfg.checkpoints)
    return list(range(cfg.initial_runs + cfg.n_round, cfg.checkpoints[-1] + 1, cfg.n_round))


def _oracle(ctx: Context, seed: int, name: str) -> dict:
    cfg, pool, learner = ctx.config, ctx.bank.pool, ctx.learner
    init = np.zeros(len(pool), bool)
    init[initial_rows(pool.collided, cfg.initial_runs, seed)] = True
    used = init.copy()
    monitor = learner.checkpoint(ctx.bank.windows(pool.scenario_id[used]),
                                 training_seed(seed, cfg.initial_runs))
    g0 = ctx.scratch_figures(pool.scenario_id[used], cfg.initial_runs, seed, monitor)
    out: dict = {"budgets": {str(cfg.initial_runs): {"scratch": g0}}, "kinds": []}
    for step, budget in enumerate(steps(cfg)):
        rng = np.random.default_rng([seed, 99, step])
        size = budget - int(used.sum())
        best = None
        for kind, rows in _candidates(ctx, monitor, used, size, rng, name == ORACLE_UNIFORM):
            ids = [*pool.scenario_id[used], *pool.scenario_id[rows]]
            candidate = learner.checkpoint(ctx.bank.windows(ids), training_seed(seed, budget))
            auprc = oracle_auprc(ctx, candidate)
            ctx.say(f"{ctx.regime}: {name} seed {seed} at {budget}: {kind} {auprc:.3f}")
            if best is None or auprc > best[0]:
                best = (auprc, kind, rows, candidate)
        auprc, kind, rows, monitor = best
        used[rows] = True
        out["kinds"].append(kind)
        if budget in cfg.checkpoints:
            acq = used & ~init
            out["budgets"][str(budget)] = {
                "scratch": learner.judge(monitor), "chosen": kind, "oracle_auprc": auprc,
                "acquired": acquired_summary(pool.collided[acq], pool.fitness[acq])}
    return out


def run_seeds_control(ctx: Context, seed: int) -> dict:
    """The best-of-k-training-seeds control's curve at one seed (a ledger unit; module doc)."""
    inputs = {**_key(ctx, ORACLE_SEEDS, seed), "n_round": ctx.config.n_round}
    return ctx.ledger.remember("efficiency-curve", inputs, lambda: _seeds_control(ctx, seed))


def _seeds_control(ctx: Context, seed: int) -> dict:
    cfg, pool, learner = ctx.config, ctx.bank.pool, ctx.learner
    picks = blind_picks(ctx, "uniform", seed, cfg.checkpoints[-1])
    collided = dict(zip(pool.scenario_id, pool.collided, strict=True))
    fitness = dict(zip(pool.scenario_id, pool.fitness, strict=True))
    g0 = ctx.scratch_figures(picks[: cfg.initial_runs], cfg.initial_runs, seed)
    out: dict = {"budgets": {str(cfg.initial_runs): {"scratch": g0}}, "kinds": []}
    for budget in cfg.checkpoints:
        train, tseed = ctx.bank.windows(picks[:budget]), training_seed(seed, budget)
        scored = []
        for j in range(cfg.oracle_candidates):
            candidate = learner.checkpoint(train, tseed + j * SEED_STRIDE)
            scored.append((oracle_auprc(ctx, candidate), candidate))
            ctx.say(f"{ctx.regime}: {ORACLE_SEEDS} seed {seed} at {budget}: training seed "
                    f"{j} {scored[-1][0]:.3f}")
        j = int(np.argmax([a for a, _ in scored]))  # the first of equals
        acquired = picks[cfg.initial_runs: budget]
        out["kinds"].append(f"seed-{j}")
        out["budgets"][str(budget)] = {
            "scratch": learner.judge(scored[j][1]), "chosen": f"seed-{j}",
            "oracle_auprc": scored[j][0], "candidates_auprc": [a for a, _ in scored],
            "acquired": acquired_summary(np.array([collided[s] for s in acquired]),
                                         np.array([fitness[s] for s in acquired]))}
    return out
