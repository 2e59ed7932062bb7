"""The study as a part of `evoeye results`: every regime's curves, summarised and checked.

For each regime: its curves (`runner.run_regime`), three summaries — Test Set AUPRC of the
monitors trained from scratch (the study's measure), boundary-set AUPRC of the same monitors,
and Test Set AUPRC of the per-round monitor when it is replay-updated — and where each
strategy's acquired runs fell and how many failures they held at each checkpoint
(`found.py`), and where a strategy's runs carry their exact p/q (`ce-is`), its unbiased
estimate of the failure rate under p against Uniform's at equal budget. The curves keep their
figures per seed and budget (the acquired ids stay in the ledger).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import NO_UPDATE, EfficiencyConfig
from evoeye.results.efficiency.findings import efficiency_findings
from evoeye.results.efficiency.found import failure_rates, failures_found
from evoeye.results.efficiency.runner import run_regime
from evoeye.results.efficiency.summary import summarise
from evoeye.results.ledger import Ledger

SUMMARIES = (("test", "scratch"), ("boundary", "scratch"), ("test", "update"))


def where_sampled(curves: dict[str, dict[str, dict]], budget: int) -> dict[str, dict]:
    """Per strategy, the mean over seeds of where its acquired runs fell at `budget`."""
    out = {}
    for name, seeds in curves.items():
        rows = [c["budgets"].get(str(budget), {}).get("acquired") for c in seeds.values()]
        rows = [r for r in rows if r and r["runs"]]
        if not rows:
            continue
        gaps = [r["mean_gap_m"] for r in rows if r["mean_gap_m"] is not None]
        out[name] = {"runs": float(np.mean([r["runs"] for r in rows])),
                     "by_gap": [float(v) for v in np.mean(
                         [np.array(r["safe_by_gap"]) / r["runs"] for r in rows], axis=0)],
                     "collided": float(np.mean([r["collided"] / r["runs"] for r in rows])),
                     "near_miss": float(np.mean([r["near_miss_2m"] / r["runs"] for r in rows])),
                     "mean_gap_m": float(np.mean(gaps)) if gaps else None}
    return out


def regime_results(result: dict, config: EfficiencyConfig) -> dict:
    """A regime's curves (figures only), summaries and where-sampled table."""
    curves = {name: {seed: {"budgets": c["budgets"], "kinds": c.get("kinds", [])}
                     for seed, c in seeds.items()}
              for name, seeds in result["curves"].items()}
    summaries = {}
    for set_name, kind in SUMMARIES:
        if kind == "update" and config.update == "retrain":
            continue  # the per-round monitor at a checkpoint is the from-scratch one
        chosen = {k: v for k, v in curves.items() if kind == "scratch" or k not in NO_UPDATE}
        summaries[f"{set_name}/{kind}"] = summarise(
            chosen, config.seeds, config.initial_runs, config.checkpoints,
            config.reference_checkpoints, kind, (set_name, "auprc"))
    out = {"sets": result["sets"], "curves": curves, "summaries": summaries,
           "where": where_sampled(curves, config.checkpoints[-1]),
           "found": {str(b): failures_found(curves, b) for b in config.checkpoints},
           "failed": result.get("failed", [])}
    if any("failure_rate" in b.get("acquired", {}) for seeds in curves.values()
           for c in seeds.values() for b in c["budgets"].values()):
        out["rates"] = {str(b): failure_rates(curves, b) for b in config.checkpoints}
    return out


def regime_part(root: DataRoot, regime: str, config: EfficiencyConfig, *, workers: int = 1,
                say: Callable[[str], None] | None = None, ledger: Ledger | None = None) -> dict:
    """One regime's data, curves and summaries."""
    return regime_results(run_regime(root, regime, config, workers=workers, say=say,
                                     ledger=ledger), config)


def failed_units(results: dict) -> list[str]:
    """"regime: strategy seed k: error" of every curve that failed, over the regimes."""
    return [f"{regime}: {f['strategy']} seed {f['seed']}: {f['error']}"
            for regime, r in results["regimes"].items() for f in r.get("failed", [])]


def study_results(config: EfficiencyConfig, regimes: dict[str, dict]) -> dict:
    """{"config", "regimes": {regime: results}, "findings"} of the regimes' results."""
    out = {"config": config.to_dict(), "regimes": regimes}
    out["findings"] = efficiency_findings(out)
    return out


def run_efficiency(root: DataRoot, config: EfficiencyConfig, *, workers: int = 1,
                   say: Callable[[str], None] | None = None,
                   ledger: Ledger | None = None) -> dict:
    """Every regime of the study, then its findings (`study_results`)."""
    return study_results(config, {regime: regime_part(root, regime, config, workers=workers,
                                                      say=say, ledger=ledger)
                                  for regime in config.regimes})
