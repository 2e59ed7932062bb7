"""What the sample-efficiency study shows, claim by claim, over its regimes.

Each check is one strategy against Uniform on one regime, on the study's measure (Test Set
AUPRC of the monitor trained from scratch, `summary.py`):
* the area under the curve: **reproduces** when the mean paired difference is positive, its
  95 % CI lies above 0 and the Wilcoxon p ≤ 0.05 (`evoeye.results.findings.check_verdict`),
  **reversed** when all three say the opposite, otherwise **not shown**;
* sample efficiency: **reproduces** when Uniform needs at least 1.5× the strategy's budget for
  its final figure and the bootstrap CI of that factor lies above 1; **reversed** when the CI
  lies below 1.

The claims: a strategy beyond the paper (not Uniform, not Sobol — a better Uniform — not the
paper's loop, not the oracle) beats Uniform on the area in at least two regimes; one reaches
Uniform's final figure with at most 2/3 of its runs in at least one regime; the oracle's area
lies above Uniform's (choosing runs can gain at all here); the oracle's area lies above its
uniform-only control's (choosing the kind of run gains more than a best-of-k choice among
uniform draws); the oracle's area lies above its best-of-k-training-seeds control's (choosing
runs gains more than picking the luckiest training seed on Uniform's runs); and the paper's
loop beats Uniform. `qbc` is a pool-mode diagnostic (it scores runs simulated already), not a
strategy beyond the paper: its checks against Uniform are in the tables, not in a claim.
A claim over regimes reproduces when enough regimes reproduce; it is not run yet when the
study has no check of it.

A study too big for one session runs regime by regime: runs with the same protocol (their
config but for regimes, seeds and strategies) are one study, and `merge_studies` checks its
claims over all their regimes. Each regime's checks stay paired over that regime's own seeds,
so a regime may have more seeds than another; a regime in two runs of one study is refused by
name (which of the two counts would be a choice).
"""

from __future__ import annotations

from evoeye.results.efficiency.config import (
    DIAGNOSTICS,
    ORACLE,
    ORACLE_SEEDS,
    ORACLE_UNIFORM,
    REFERENCE,
    EfficiencyConfig,
)
from evoeye.results.efficiency.summary import VERSUS
from evoeye.results.findings import (
    AGAINST,
    NOT_RUN,
    NOT_SHOWN,
    REPRODUCES,
    REVERSED,
    check_verdict,
)
from evoeye.results.merge import merge_runs

MEASURE = "test/scratch"
EFFICIENCY = 1.5
# not "beyond the paper"
BASELINES = (REFERENCE, "sobol", "evoeye", ORACLE, ORACLE_UNIFORM, ORACLE_SEEDS, *DIAGNOSTICS)


class StudyMergeError(ValueError):
    """Runs of one study that cannot be checked together (module doc)."""


def efficiency_verdict(e: dict | None) -> str:
    """The verdict of one sample-efficiency factor (module doc)."""
    if not e or e.get("factor") is None:
        return NOT_SHOWN
    if e["factor"] >= EFFICIENCY and e["low"] > 1.0:
        return REPRODUCES
    return REVERSED if e["high"] < 1.0 else NOT_SHOWN


def _checks(results: dict) -> list[dict]:
    out = []
    for regime, r in results["regimes"].items():
        for name, s in r["summaries"][MEASURE]["strategies"].items():
            if name == REFERENCE or "area_vs_reference" not in s:
                continue
            area = s["area_vs_reference"]
            out.append({"regime": regime, "strategy": name, "area": area,
                        "area_verdict": check_verdict(area, "better"),
                        "efficiency": s.get("efficiency"),
                        "efficiency_verdict": efficiency_verdict(s.get("efficiency"))})
    return out


def _control_checks(results: dict, control: str) -> list[dict]:
    """The oracle against one of its controls, per regime (area only)."""
    out = []
    for regime, r in results["regimes"].items():
        vs = r["summaries"][MEASURE]["strategies"].get(ORACLE, {}).get(
            f"area_vs_{VERSUS[control]}")
        if vs:
            out.append({"regime": regime, "strategy": ORACLE, "against": control,
                        "area": vs,
                        "area_verdict": check_verdict(vs, "better"), "efficiency": None,
                        "efficiency_verdict": NOT_SHOWN})
    return out


def _claim(id_: str, claim: str, checks: list[dict], key: str, need: int) -> dict:
    """A claim that holds when one strategy reproduces in `need` regimes (none reversed)."""
    if not checks:
        return {"id": id_, "claim": claim, "checks": [], "verdict": NOT_RUN}
    by_strategy: dict[str, list[str]] = {}
    for c in checks:
        by_strategy.setdefault(c["strategy"], []).append(c[key])
    best = max(sum(v == REPRODUCES for v in vs) for vs in by_strategy.values())
    if best >= need:
        verdict = REPRODUCES
    elif all(v == REVERSED for vs in by_strategy.values() for v in vs):
        verdict = AGAINST
    else:
        verdict = NOT_SHOWN
    return {"id": id_, "claim": claim, "checks": checks, "verdict": verdict}


def efficiency_findings(results: dict) -> list[dict]:
    """The study's claims with their checks and verdicts (module doc)."""
    checks = _checks(results)
    new = [c for c in checks if c["strategy"] not in BASELINES]
    return [
        _claim("efficiency-area", "A strategy beyond the paper beats Uniform on the area under "
               "the Test-Set AUPRC curve in at least two regimes", new, "area_verdict", 2),
        _claim("efficiency-factor", "A strategy beyond the paper reaches Uniform's final AUPRC "
               f"with at most 2/3 of its runs (≥ {EFFICIENCY}×) in at least one regime", new,
               "efficiency_verdict", 1),
        _claim("efficiency-ceiling", "Choosing runs can gain over Uniform: the oracle's area "
               "lies above Uniform's (in every regime)",
               [c for c in checks if c["strategy"] == ORACLE], "area_verdict",
               len(results["regimes"])),
        _claim("efficiency-choice", "Choosing the kind of run gains more than choosing among "
               "uniform draws: the oracle's area lies above its uniform-only control's (in "
               "every regime)", _control_checks(results, ORACLE_UNIFORM), "area_verdict",
               len(results["regimes"])),
        _claim("efficiency-seeds", "Choosing runs gains more than picking the luckiest "
               "training seed: the oracle's area lies above its best-of-k-training-seeds "
               "control's (in every regime)", _control_checks(results, ORACLE_SEEDS),
               "area_verdict", len(results["regimes"])),
        _claim("efficiency-paper", "The paper's loop (evoeye) beats Uniform on the area (in "
               "at least two regimes)", [c for c in checks if c["strategy"] == "evoeye"],
               "area_verdict", 2),
    ]


def merge_studies(runs: list[dict]) -> list[dict]:
    """Runs ({"path", "config", "findings", "regimes"}: a results JSON's `efficiency` part and
    its file) as studies ({"paths", "config", "findings"}): runs of one protocol merged, their
    claims checked over every regime (module doc, `evoeye.results.merge`)."""
    return merge_runs(runs, EfficiencyConfig().to_dict(), efficiency_findings,
                      StudyMergeError, noun="study")
