"""The testing-efficiency protocol as a part of `evoeye results`: every curve, then each
regime's summary (`summary.py`) and claims (`findings.py`).

Every curve is a ledger unit (`RareConfig.unit` and the software version): a killed
protocol resumes with the curves it had not finished, and a re-run computes nothing. Curves run
seed-major in worker processes, so a protocol stopped early has whole seeds. A curve that raises
is named with its error and left out; the others go on, and a re-run retries it alone.

With the learning side (`RareConfig.learn`), each regime's recorded curves are then learned
from (`learn.py`; each learned curve a ledger unit too) and the regime's summary gains
`learning` (`learn.summarise_learning`, with the sets' sizes and the config).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from evoeye import __version__
from evoeye.lifeline import die_with_parent, pool_context
from evoeye.paths import DataRoot
from evoeye.results.ledger import Ledger
from evoeye.results.rare.config import RareConfig
from evoeye.results.rare.runner import run_curve
from evoeye.results.rare.summary import found_pooled, summarise

KIND = "rare-curve"
Say = Callable[[str], None]


def _unit(args: tuple[str, RareConfig, str, str, int]) -> tuple[str, str, int, dict, bool]:
    """(regime, strategy, seed, curve or {"error"}, computed now) of one curve."""
    root, config, regime, strategy, seed = args
    ledger = Ledger(DataRoot(Path(root)))
    try:
        curve = ledger.remember(KIND, {**config.unit(regime, strategy, seed),
                                       "software_version": __version__},
                                lambda: run_curve(config, regime, strategy, seed))
    except Exception as exc:  # noqa: BLE001 — one curve's failure must not stop the others
        return regime, strategy, seed, {"error": f"{type(exc).__name__}: {exc}"}, False
    return regime, strategy, seed, curve, bool(ledger.computed)


def run_rare(root: DataRoot, config: RareConfig, *, workers: int = 1,
             say: Say | None = None) -> dict:
    """Every curve of every regime and their summaries: {"config", "regimes": {regime:
    summary}, "failed": [{"regime", "strategy", "seed", "error"}], "computed": n}."""
    say = say or (lambda msg: None)
    todo = [(str(root.path), config, regime, strategy, seed) for regime in config.regimes
            for seed in config.seeds for strategy in config.strategies]
    curves: dict[str, dict[str, dict[str, dict]]] = {r: {} for r in config.regimes}
    failed: list[dict] = []
    computed = 0

    def keep(regime: str, strategy: str, seed: int, curve: dict, now: bool) -> None:
        nonlocal computed
        computed += now
        if "error" in curve:
            failed.append({"regime": regime, "strategy": strategy, "seed": seed,
                           "error": curve["error"]})
            say(f"{regime}: {strategy} seed {seed} FAILED: {curve['error']}")
            return
        curves[regime].setdefault(strategy, {})[str(seed)] = curve
        hits = sum(r["collided"] for r in curve["runs"])
        say(f"{regime}: {strategy} seed {seed}: {hits} collisions in {len(curve['runs'])} runs")

    if workers == 1:
        for done in map(_unit, todo):
            keep(*done)
    else:
        with ProcessPoolExecutor(workers, mp_context=pool_context(), initializer=die_with_parent,
                                 initargs=(os.getpid(),)) as pool:
            for done in pool.map(_unit, todo):
                keep(*done)
    regimes = {r: summarise(curves[r], config) for r in config.regimes}
    if config.learn is not None:
        from evoeye.results.rare.learn import learn_regime, summarise_learning  # loads torch

        for regime in config.regimes:
            learned = learn_regime(root, regime, curves[regime], config, workers=workers,
                                   say=say)
            failed += [{**f, "regime": regime, "strategy": f"{f['strategy']} (learning)",
                        "learning": True} for f in learned["failed"]]
            regimes[regime]["learning"] = summarise_learning(learned)
            if "stream_runs" in (test := learned["sets"]["test"]):
                regimes[regime]["found_pooled"] = found_pooled(
                    curves[regime], test["stream_runs"], test["stream_collisions"])
    return {"config": config.to_dict(), "software_version": __version__,
            "regimes": regimes, "failed": failed, "computed": computed}


def rare_results(root: DataRoot, config: RareConfig, *, workers: int = 1,
                 say: Say | None = None) -> tuple[dict, int]:
    """`run_rare`'s results with the claims checked over its regimes (`findings.py`), and
    the curves computed now (kept out of the results: a re-run writes the same ones)."""
    from evoeye.results.rare.findings import rare_findings

    out = run_rare(root, config, workers=workers, say=say)
    computed = out.pop("computed")
    out["findings"] = rare_findings(out)
    return out, computed


def failed_curves(rare: dict) -> list[str]:
    """"regime: strategy seed k: error" of every curve that failed."""
    return [f"{f['regime']}: {f['strategy']} seed {f['seed']}: {f['error']}"
            for f in rare.get("failed", [])]
