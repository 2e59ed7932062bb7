"""The study over its regimes: each regime's data, then every curve (strategy × seed, the
oracle's and its control's) in worker processes, seed-major so a study stopped early has
whole seeds.

A regime's sets are loaded once in the parent; the workers are forked from it and read them
without a copy (the frame features are numpy arrays the children never write). Every curve is
a ledger unit (`curves.py`), so a killed study resumes with the curves it had not finished.
A curve that raises is named with its error and left out (its seed missing from that
strategy's summaries); the other curves go on, and a re-run retries it alone.
"""

from __future__ import annotations

import hashlib
import multiprocessing as mp
import os
from collections import Counter
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from evoeye.lifeline import die_with_parent
from evoeye.monitor.recipes import recipe_params
from evoeye.monitor.threads import intra_op_threads
from evoeye.paths import DataRoot
from evoeye.results.efficiency.acquire import Bank, PoolAcquirer, SimAcquirer
from evoeye.results.efficiency.config import (
    CEILINGS,
    ORACLE_SEEDS,
    ORACLE_UNIFORM,
    QBC,
    EfficiencyConfig,
    parse_regime,
)
from evoeye.results.efficiency.curves import Context, run_curve
from evoeye.results.efficiency.data import prepare_regime
from evoeye.results.efficiency.learner import Learner
from evoeye.results.efficiency.oracle import run_oracle, run_seeds_control
from evoeye.results.efficiency.qbc import run_qbc
from evoeye.results.efficiency.sets import JUDGING_SETS, RegimeData
from evoeye.results.ledger import Ledger
from evoeye.scenarios import get_scenario

Say = Callable[[str], None]
_CONTEXT: Context | None = None  # the regime a forked worker inherits


def sets_fingerprint(data: RegimeData) -> str:
    """sha256 of the run ids of every set a curve reads (pool, val, oracle, Test, boundary)."""
    h = hashlib.sha256()
    for name, ids in (("pool", data.pool.scenario_id),
                      *((k, sorted(set(w.scenario_id.tolist()))) for k, w in data.sets.items())):
        h.update(f"{name}\n".encode() + "\n".join(map(str, ids)).encode())
    return h.hexdigest()


def set_sizes(data: RegimeData) -> dict[str, dict[str, int]]:
    """Runs, collisions, frames and unsafe frames of the pool and of every set."""
    out = {"pool": {"runs": len(data.pool), "collisions": int(data.pool.collided.sum()),
                    "frames": len(data.pool_windows),
                    "unsafe": int(data.pool_windows.label.sum())}}
    for name, w in data.sets.items():
        ids = np.unique(w.scenario_id)
        out[name] = {"runs": len(ids), "frames": len(w), "unsafe": int(w.label.sum())}
    return out


def _unit(unit: tuple[str, int]) -> tuple[str, int, dict, Counter, Counter]:
    """(strategy, seed, curve, ledger units found, computed), the curve {"error": …} when it
    raised (module doc). The counts let a parent add up what its forked workers did."""
    strategy, seed = unit
    ctx = _CONTEXT
    assert ctx is not None, "a worker needs the regime's context"
    found, computed = Counter(ctx.ledger.found), Counter(ctx.ledger.computed)
    try:
        curve = _curve(ctx, strategy, seed)
    except Exception as exc:  # noqa: BLE001 — one curve's failure must not stop the others
        curve = {"error": f"{type(exc).__name__}: {exc}"}
    return strategy, seed, curve, ctx.ledger.found - found, ctx.ledger.computed - computed


def _curve(ctx: Context, strategy: str, seed: int) -> dict:
    with intra_op_threads():
        if strategy == ORACLE_SEEDS:
            return run_seeds_control(ctx, seed)
        if strategy in CEILINGS:
            return run_oracle(ctx, seed, control=strategy == ORACLE_UNIFORM)
        if strategy == QBC:  # pool mode only (the config refuses it in generative mode)
            return run_qbc(ctx, seed)
        if ctx.config.mode == "pool":
            acquirer = PoolAcquirer(ctx.bank)
        else:
            acquirer = SimAcquirer(ctx.bank, ctx.regime, strategy, 5, ctx.config.horizon_s)
        return run_curve(ctx, strategy, seed, acquirer)


def units(config: EfficiencyConfig) -> list[tuple[str, int]]:
    """Every curve of a regime, seed-major; the oracle's and its controls' in pool mode only."""
    extra = CEILINGS if config.oracle and config.mode == "pool" else ()
    return [(s, seed) for seed in config.seeds for s in (*config.strategies, *extra)]


def run_regime(root: DataRoot, regime: str, config: EfficiencyConfig, *, workers: int = 1,
               say: Say | None = None, ledger: Ledger | None = None) -> dict:
    """A regime's data and every curve: {"sets": sizes, "curves": {strategy: {seed: curve}},
    "failed": [{"strategy", "seed", "error"}]}."""
    global _CONTEXT
    say = say or (lambda msg: None)
    data_root = prepare_regime(root, regime, config, workers=workers, say=say)
    say(f"{regime}: loading its sets")
    data = RegimeData.load(data_root, config)
    learner = Learner(data.sets["val"], {k: data.sets[k] for k in JUDGING_SETS},
                      recipe_params(config.recipe, **config.train_overrides), config.members)
    _CONTEXT = ctx = Context(regime, get_scenario(parse_regime(regime)[0]), config, learner,
                             Bank(data), ledger or Ledger(root), sets_fingerprint(data), say)
    curves: dict[str, dict[str, dict]] = {}
    failed: list[dict] = []

    def keep(strategy: str, seed: int, curve: dict, found: Counter, computed: Counter) -> None:
        if workers > 1:  # a forked worker counted in its own copy of the ledger
            ctx.ledger.found.update(found)
            ctx.ledger.computed.update(computed)
        if "error" in curve:
            failed.append({"strategy": strategy, "seed": seed, "error": curve["error"]})
            say(f"{regime}: {strategy} seed {seed} FAILED: {curve['error']}")
        else:
            curves.setdefault(strategy, {})[str(seed)] = curve

    try:
        if workers == 1:
            for done in map(_unit, units(config)):
                keep(*done)
        else:
            with ProcessPoolExecutor(workers, mp_context=mp.get_context("fork"),
                                     initializer=die_with_parent,
                                     initargs=(os.getpid(),)) as pool:
                for done in pool.map(_unit, units(config)):
                    keep(*done)
    finally:
        _CONTEXT = None
    return {"regime": regime, "sets": set_sizes(data), "curves": curves, "failed": failed}
