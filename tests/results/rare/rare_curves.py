"""Synthetic rare-failure curves whose figures are known by construction, and the `rare` part
of a results JSON built from them through the real summary and claims (no simulation; each
kind of regime is summarised once per session: the bootstraps take a second)."""

from __future__ import annotations

import math
from functools import cache

from evoeye.results.rare.config import RareConfig
from evoeye.results.rare.findings import rare_findings
from evoeye.results.rare.summary import summarise

RUNS = 200
RARE, COMMON = "highway-cut-in:cautious", "occluded-crossing:cautious"


def make_curve(hits: int, runs: int = RUNS, weight: float | None = None,
               kind: str = "cut-in") -> dict:
    """A curve whose first `hits` runs collide; `weight`: every run's p/q (None: drawn from p)."""
    log_q = [None if weight is None else -math.log(weight)] * runs
    return {"x": [[0.0]] * runs, "log_q": log_q,
            "log_p": [None if q is None else 0.0 for q in log_q],
            "runs": [{"collided": i < hits, "mechanism": kind if i < hits else None,
                      "cause": "perception" if i < hits else None} for i in range(runs)]}


def rare_curves(seeds: int = 20) -> dict[str, dict[str, dict]]:
    """≈ 0.2 % under p: Uniform finds one failure on 8 of the seeds; ce-is finds 8–12 per seed
    at weight 0.04 (its estimate 0.16–0.24 %: unbiased, far less spread than Uniform's)."""
    return {"uniform": {str(s): make_curve(int(s % 5 < 2)) for s in range(seeds)},
            "ce-is": {str(s): make_curve(8 + s % 5, weight=0.04) for s in range(seeds)}}


def common_curves(seeds: int = 20) -> dict[str, dict[str, dict]]:
    """1 % under p: Uniform and Sobol both find 2 per 200 at every seed (ratio 1)."""
    return {"uniform": {str(s): make_curve(2) for s in range(seeds)},
            "sobol": {str(s): make_curve(2, kind="crossing") for s in range(seeds)}}


def blind_curves() -> dict[str, dict[str, dict]]:
    """ce-is's rare curves against a Uniform that finds nothing at any seed."""
    return {"uniform": {str(s): make_curve(0) for s in range(20)},
            "ce-is": rare_curves()["ce-is"]}


KINDS = {"rare": rare_curves, "common": common_curves, "blind": blind_curves}


@cache
def summary_of(kind: str) -> dict:
    """The summary of one kind of regime (KINDS)."""
    return summarise(KINDS[kind](), RareConfig())


def rare_part(regimes: dict[str, str], **config) -> dict:
    """The `rare` part of a results JSON over regimes of these kinds ({regime: kind})."""
    config = RareConfig(regimes=tuple(regimes), seeds=tuple(range(20)), **config)
    out = {"config": config.to_dict(), "software_version": "test",
           "regimes": {r: summary_of(kind) for r, kind in regimes.items()}, "failed": []}
    out["findings"] = rare_findings(out)
    return out



def two_regimes() -> dict:
    """The rare regime (ce-is) and the common one (Sobol) as one protocol run."""
    return rare_part({RARE: "rare", COMMON: "common"}, strategies=("uniform", "ce-is", "sobol"))
