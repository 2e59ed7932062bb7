"""One learning curve: a strategy acquires runs round by round from D_init, and at every
checkpoint the monitor is trained from scratch on all of them and judged.

The loop per round: the strategy proposes N_round runs one at a time, each is acquired (taken
from the pool, or simulated: `acquire.py`) and told to it; then the per-round monitor whose
feedback the strategies read (and, for `disagreement`, the committee beside it) is updated —
by the replay fine-tune (the paper's loop, `evoeye evolve --update replay`), or with
`update="retrain"` trained again from scratch on every run so far, with the seed a checkpoint
at that many runs gets (so at a checkpoint it is the checkpoint's monitor) — and every
record's feedback is refreshed. Under `retrain` a strategy that reads no feedback keeps no
per-round monitor: nothing would read it.

At a checkpoint two monitors are judged on the sets no strategy shaped: one trained from
scratch on everything acquired (the curve's figure — what the runs are worth, and what
`evoeye evolve` deploys by default), with the seed of that seed and checkpoint that every
strategy shares, and the per-round monitor (under `replay` what the paper's loop would deploy;
under `retrain` the same monitor as the first).

The same seed gives every strategy the same D_init (drawn from the pool), the same G_0 and the
same training seed at each checkpoint, so strategies differ only in the runs they chose.
A from-scratch training is a ledger unit keyed by the runs it read and its seed, and a finished
curve is one too, so a re-run redoes neither; an unfinished curve replays its trajectory (the
same picks, the same updates: everything is seeded).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from evoeye.evaluation.failure_rate import failure_rate
from evoeye.evolve.search.protocol import propose_ahead
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.registry import (
    FEEDBACK_BLIND,
    READS_DISAGREEMENT,
    make_strategy,
    strategy_options,
)
from evoeye.monitor.ensemble import EnsembleMonitor
from evoeye.monitor.fusion import FusionMonitor
from evoeye.results.efficiency.acquire import Acquirer, Bank, PoolAcquirer
from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.efficiency.learner import (
    Learner,
    replay_sample,
    run_disagreement,
    run_feedback,
)
from evoeye.results.ledger import Ledger
from evoeye.scenarios import LogicalScenario

COMMITTEE = 3  # members of the disagreement strategy's committee (the monitor and 2 more)
Say = Callable[[str], None]


def initial_rows(collided: np.ndarray, n: int, seed: int) -> np.ndarray:
    """The pool rows of a seed's D_init (sorted): the same for every strategy. `n` rows drawn
    uniformly from the pool (`collided`: its runs' outcomes), drawn again from the same seeded
    stream until one of them collided — no monitor trains on a set without a collision, which
    in the rare-failure regime is about one draw of 40 in four (a seed whose first draw had a
    collision keeps it). ValueError if the pool has none."""
    collided = np.asarray(collided, bool)
    if not collided.any():
        raise ValueError("the pool holds no collision run: no initial set can train a monitor")
    rng = np.random.default_rng([seed, 0])
    while True:
        rows = np.sort(rng.choice(len(collided), size=n, replace=False))
        if collided[rows].any():
            return rows


def training_seed(seed: int, budget: int) -> int:
    """The training seed of a from-scratch monitor at a checkpoint: shared by the strategies."""
    return seed * 100_003 + budget


def members_key(members: int) -> dict[str, int]:
    """What a ledger key adds for the checkpoint monitors' ensemble size: nothing for one
    monitor (the keys of single-monitor units are as they always were)."""
    return {} if members == 1 else {"members": members}


def ids_digest(ids) -> str:
    return hashlib.sha256("\n".join(sorted(map(str, ids))).encode()).hexdigest()


@dataclass
class Context:
    """What every curve of one regime shares."""

    regime: str
    space: LogicalScenario
    config: EfficiencyConfig
    learner: Learner
    bank: Bank  # the windows and outcomes of every run a curve can hold
    ledger: Ledger
    fingerprint: str  # of the regime's sets: a unit that read them is keyed by it
    say: Say = field(default=lambda msg: None)

    def scratch_figures(self, ids, budget: int, seed: int,
                        monitor: FusionMonitor | EnsembleMonitor | None = None,
                        weights: dict[str, float] | None = None,
                        first: FusionMonitor | None = None) -> dict:
        """{set: metrics} of the checkpoint's monitor trained from scratch on `ids` with the
        checkpoint's seed (`Learner.checkpoint`; a ledger unit; `monitor`: that very monitor,
        if built already; `first`: its member 0, if trained already; `weights`: the runs' p/q,
        which train it if the recipe says so, and key it then)."""
        tseed = training_seed(seed, budget)
        inputs = {"regime": self.regime, "sets": self.fingerprint, "runs": ids_digest(ids),
                  "n": len(ids), "seed": tseed, "recipe": self.learner.recipe}
        if self.learner.params.importance_weights:
            inputs["weights"] = ids_digest(f"{s}={(weights or {}).get(s, 1.0)!r}" for s in ids)
        inputs.update(members_key(self.learner.members))

        def train() -> dict:
            self.say(f"{self.regime}: from scratch on {len(ids)} runs, seed {tseed}")
            trained = monitor or self.learner.checkpoint(self.bank.windows(ids), tseed, weights,
                                                         first)
            return self.learner.judge(trained)

        return self.ledger.remember("efficiency-scratch", inputs, train)


@dataclass
class Trajectory:
    """A curve in progress: the records, the monitor (and committee) and what was picked."""

    records: Records
    monitor: FusionMonitor | None  # None while only the picks are replayed (`blind_picks`)
    committee: list[FusionMonitor]
    kinds: list[str]  # how each acquired run was chosen (the proposal's kind)


MARGIN_BINS_M = (0.5, 1.0, 2.0, 4.0, 7.0)  # upper edges of the safe runs' gap bins; then ≥ 7


def acquired_summary(collided: np.ndarray, fitness: np.ndarray,
                     ratio: np.ndarray | None = None) -> dict:
    """Where acquired runs fell: how many collided, how near the boundary the others came
    (their criticality × 10 m is the footprint gap, capped at 10 m), and the safe runs per
    gap bin (MARGIN_BINS_M); with the runs' exact p/q (`ratio`, an importance-sampling
    strategy's), the unbiased estimate of P(collision) under p they give (`failure_rate`)."""
    collided = np.asarray(collided, bool)
    gap = np.asarray(fitness, float) * 10.0
    safe = ~collided
    bins = np.bincount(np.searchsorted(MARGIN_BINS_M, gap[safe], side="right"),
                       minlength=len(MARGIN_BINS_M) + 1)
    out = {"runs": int(len(collided)), "collided": int(collided.sum()),
           "safe_by_gap": [int(b) for b in bins],
           "near_miss_2m": int((safe & (gap < 2.0)).sum()),
           "mean_gap_m": float(np.nanmean(np.where(safe, gap, np.nan))) if safe.any() else None}
    if ratio is not None:
        out["failure_rate"] = failure_rate(collided, ratio).to_dict()
    return out


def exact_ratio(records: Records, start: int) -> np.ndarray | None:
    """p/q of the records from `start` on if every one of them carries its proposal's
    density (an importance-sampling strategy's runs), else None."""
    acquired = records.tail(start)
    return acquired.importance_ratio() if np.isfinite(acquired.log_q).all() else None



def run_curve(ctx: Context, strategy: str, seed: int, acquirer: Acquirer) -> dict:
    """One strategy's learning curve at one seed (a ledger unit: found, or computed)."""
    cfg = ctx.config
    inputs = {"regime": ctx.regime, "sets": ctx.fingerprint, "strategy": strategy,
              "seed": seed, "mode": acquirer.mode, "initial": cfg.initial_runs,
              "budgets": list(cfg.checkpoints_of(strategy)), "n_round": cfg.n_round,
              "recipe": ctx.learner.recipe}
    if cfg.update != "replay":  # replay curves keep the keys they were ledgered under
        inputs["update"] = cfg.update
    inputs.update(members_key(cfg.members))
    return ctx.ledger.remember("efficiency-curve", inputs,
                               lambda: _curve(ctx, strategy, seed, acquirer))


def initial_records(ctx: Context, seed: int) -> Records:
    """The records of a seed's D_init (`initial_rows`), unscored."""
    pool = ctx.bank.pool
    rows = initial_rows(pool.collided, ctx.config.initial_runs, seed)
    return Records(params=pool.params[rows], feedback=np.full(len(rows), np.nan),
                   fitness=pool.fitness[rows], collided=pool.collided[rows],
                   duration_s=pool.duration_s[rows], scenario_id=pool.scenario_id[rows])


def _start(ctx: Context, seed: int, reads_disagreement: bool) -> Trajectory:
    learner, records = ctx.learner, initial_records(ctx, seed)
    train = ctx.bank.windows(records.scenario_id)
    monitor = learner.scratch(train, training_seed(seed, ctx.config.initial_runs))
    committee = [monitor, *(learner.scratch(train, training_seed(seed, 50_000 + j))
                            for j in range(1, COMMITTEE))] if reads_disagreement else []
    return _refreshed(ctx, Trajectory(records, monitor, committee, []))


def _acquire_round(ctx: Context, strategy, acquirer: Acquirer, t: Trajectory,
                   seed: int) -> None:
    """One round: n_round proposals, each acquired, appended to the records and told (those
    that wait on no outcome, `propose_ahead`, acquired together)."""
    done = 0
    while done < ctx.config.n_round:
        props = propose_ahead(strategy, t.records, ctx.config.n_round - done)
        runs = acquirer.acquire_all(props, seed, t.records.n - ctx.config.initial_runs)
        for prop, run in zip(props, runs, strict=True):
            t.records = t.records.append(run.x, feedback=np.nan, fitness=run.fitness,
                                         collided=run.collided, duration_s=run.duration_s,
                                         scenario_id=run.scenario_id, log_q=prop.log_q,
                                         log_p=prop.log_p)
            t.kinds.append(prop.kind)
            strategy.tell(run.x, run.fitness)
        done += len(props)


def _make(ctx: Context, name: str, seed: int, acquirer: Acquirer):
    return make_strategy(name, ctx.space, seed, pool=acquirer.pool_params,
                         **strategy_options(name, batch=ctx.config.n_round))


def blind_picks(ctx: Context, name: str, seed: int, budget: int) -> np.ndarray:
    """The scenario ids (D_init first) of a feedback-blind strategy's pool-mode curve at
    `budget` runs: its picks read no monitor, so they are replayed without training any."""
    if name not in FEEDBACK_BLIND:
        raise ValueError(f"{name!r} reads feedback: its picks need its monitors")
    acquirer = PoolAcquirer(ctx.bank)
    strategy = _make(ctx, name, seed, acquirer)
    t = Trajectory(initial_records(ctx, seed), None, [], [])
    while t.records.n < budget:
        _acquire_round(ctx, strategy, acquirer, t, seed)
    return t.records.scenario_id[:budget]


def _refreshed(ctx: Context, t: Trajectory) -> Trajectory:
    """Every record's feedback (and disagreement) under the current monitor (committee)."""
    windows = ctx.bank.windows(t.records.scenario_id)
    fb = run_feedback(t.monitor, windows)
    t.records = t.records.with_feedback(np.array([fb.get(s, np.nan)
                                                  for s in t.records.scenario_id]))
    if t.committee:
        d = run_disagreement(t.committee, windows)
        t.records = t.records.with_disagreement(np.array([d.get(s, np.nan)
                                                          for s in t.records.scenario_id]))
    return t


def _retrain(ctx: Context, t: Trajectory, seed: int) -> None:
    """The per-round monitor (and each committee member) trained again from scratch on every
    run so far, with the seed a checkpoint at that many runs gets (members: offset seeds)."""
    ids = list(t.records.scenario_id)
    train, tseed = ctx.bank.windows(ids), training_seed(seed, len(ids))
    weights = t.records.ratio_by_run()
    t.monitor = ctx.learner.scratch(train, tseed, weights)
    if t.committee:
        t.committee = [t.monitor, *(ctx.learner.scratch(train, tseed + 1_000_003 * j, weights)
                                    for j in range(1, len(t.committee)))]
    _refreshed(ctx, t)


def _update(ctx: Context, t: Trajectory, new: int, seed: int, round_: int) -> None:
    """The paper's replay update of the monitor (and each committee member) after a round."""
    records = t.records
    n_old = records.n - new
    rng = np.random.default_rng([seed, round_, 7])
    pick = replay_sample(records.scenario_id[:n_old], records.collided[:n_old], new,
                         bool(records.collided[n_old:].any()), rng)
    ids = [*records.scenario_id[pick], *records.scenario_id[n_old:]]
    train = ctx.bank.windows(ids)
    if not (train.label.any() and (~train.label.astype(bool)).any()):
        return  # one class only: nothing an update can learn from; the monitor stays
    useed = seed * 1000 + round_
    weights = records.ratio_by_run()
    t.monitor = ctx.learner.update(t.monitor, train, useed, weights)
    if t.committee:
        t.committee = [t.monitor, *(ctx.learner.update(m, train, useed + 1_000_003 * j, weights)
                                    for j, m in enumerate(t.committee[1:], start=1))]
    _refreshed(ctx, t)


def _curve(ctx: Context, strategy_name: str, seed: int, acquirer: Acquirer) -> dict:
    cfg = ctx.config
    reads = strategy_name in READS_DISAGREEMENT
    retrain = cfg.update == "retrain"
    retrains = retrain and strategy_name not in FEEDBACK_BLIND  # someone reads its monitor
    t = _start(ctx, seed, reads)
    strategy = _make(ctx, strategy_name, seed, acquirer)
    budgets = cfg.checkpoints_of(strategy_name)
    g0 = ctx.scratch_figures(t.records.scenario_id, cfg.initial_runs, seed, first=t.monitor)
    # the per-round monitor starts as member 0 of G_0 (G_0 itself when it has one member)
    u0 = g0 if cfg.members == 1 or retrain else ctx.learner.judge(t.monitor)
    out: dict = {"budgets": {str(cfg.initial_runs): {"scratch": g0, "update": u0}}}
    round_ = 0
    while t.records.n < budgets[-1]:
        round_ += 1
        _acquire_round(ctx, strategy, acquirer, t, seed)
        if retrains:
            _retrain(ctx, t, seed)
        elif not retrain:
            _update(ctx, t, cfg.n_round, seed, round_)
        if t.records.n in budgets:
            ids = list(t.records.scenario_id)
            ctx.say(f"{ctx.regime}: {strategy_name} seed {seed} at {len(ids)} runs")
            scratch = ctx.scratch_figures(ids, len(ids), seed,
                                          weights=t.records.ratio_by_run(),
                                          first=t.monitor if retrains else None)
            out["budgets"][str(len(ids))] = {
                "scratch": scratch,
                "update": scratch if retrain else ctx.learner.judge(t.monitor),
                "acquired": acquired_summary(t.records.collided[cfg.initial_runs:],
                                             t.records.fitness[cfg.initial_runs:],
                                             exact_ratio(t.records, cfg.initial_runs)),
            }
    out["acquired_ids"] = [str(s) for s in t.records.scenario_id[cfg.initial_runs:]]
    out["kinds"] = t.kinds
    acquired = t.records.tail(cfg.initial_runs)
    if np.isfinite(acquired.log_q).any():  # its runs' exact densities, to weigh them again
        out["log_q"], out["log_p"] = acquired.log_q.tolist(), acquired.log_p.tolist()
    return out
