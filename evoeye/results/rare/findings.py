"""What the rare-failure protocol shows, claim by claim, over its regimes.

Each check is one strategy against Uniform on one regime (`summary.py`'s figures), with the
paired per-seed cell it rests on (`compare_paired`'s fields: n, mean_diff, ci_low, ci_high, p):

* **rare-found** — failures found per run: the target is 10× Uniform's where the regime's
  reference failure rate is below 0.3 % (the ≈ 0.1 % regime), else 3× (≈ 1 %). It
  **reproduces** when the ratio's bootstrap CI lies at or above the target, **does not
  reproduce** when its upper end exists and lies below it, and is **not shown** otherwise (an
  open interval: Uniform found too few to bound the ratio). Cell: the paired difference of the
  seeds' failures per 100 runs.
* **rare-estimate** — the strategy's failure-rate estimate (exact p/q, or subset simulation's
  product of its levels) is unbiased and has ≥ 3× smaller relative error at equal budget: it
  **reproduces** when the bias CI against Uniform's pooled estimate contains 0 and the error
  ratio's (Uniform's / the strategy's) CI lies at or above 3; it **does not reproduce** when
  the bias CI excludes 0 or the ratio's upper end lies below 3; otherwise not shown (so where
  Uniform saw no failure: its pooled 0 has no variance to judge a bias by). Cell: the paired
  difference of the seeds' absolute relative errors (Uniform's − the strategy's).
* **rare-learn** — with the learning side (`learn.py`): the monitor trained on the strategy's
  runs (importance-weighted by their p/q) beats Uniform's on the area under the Test AUPRC
  curve. It **reproduces** when the paired difference of the areas has a 95 % CI above 0 and
  p ≤ 0.05 (`evoeye.results.findings.check_verdict`), **does not reproduce** when it is
  reversed; otherwise it is not shown, with the minimum detectable effect the seeds had (80 %
  power): a null at an MDE ≤ NULL_MDE points is the issue's stated null, a larger one is not.
  A regime whose Test Set holds fewer than its `min_test_failures` collisions is not shown
  (too few failures to judge a monitor by). Cell: the paired difference of the areas. Only
  strategies whose runs carry their exact p/q (`WEIGHTED`) are checked: the others' monitors
  train unweighted, and their comparison with Uniform is in rare.md, not in this claim.

A claim reproduces when one strategy reproduces in every regime run; does not reproduce when
every check goes against it; is partly shown when some check reproduces; not shown otherwise,
or when a strategy it is about ran but no check could be made (e.g. no failure seen, so no
estimate); not run yet when none ran.

A protocol too big for one session runs regime by regime: runs whose config agrees but for
regimes, seeds, strategies and the learning side's settings are one protocol (each regime's
learning figures carry their own config), and `merge_rare` checks its claims over all their
regimes; a regime in two runs of one protocol is refused by name.
"""

from __future__ import annotations

import math

from evoeye.results.findings import (
    AGAINST,
    NOT_RUN,
    NOT_SHOWN,
    PARTLY,
    REPRODUCES,
    REVERSED,
    check_verdict,
)
from evoeye.results.merge import merge_runs
from evoeye.results.rare.config import ESTIMATING, REFERENCE, WEIGHTED, RareConfig

RARE_BELOW = 0.003  # a regime whose reference failure rate is below this is the ≈ 0.1 % one
FOUND_TARGETS = (10.0, 3.0)  # × Uniform's failures per run: below RARE_BELOW, else
ERROR_TARGET = 3.0  # × smaller relative error at equal budget
NULL_MDE = 2.0  # AUPRC points: a null on the learning side is stated at an MDE at most this


class RareMergeError(ValueError):
    """Runs of one protocol that cannot be checked together (module doc)."""


def reference_rate(summary: dict) -> float | None:
    """A regime's failure rate under p: Uniform's pooled share (the protocol's reference), None
    where Uniform saw no failure (the rate is then unknown, and the stricter target applies)."""
    ref = (summary.get("estimates") or {}).get("reference")
    return ref["value"] if ref else None


def found_target(rate: float | None) -> float:
    """The multiple of Uniform's failures per run a strategy must reach (module doc); the
    stricter one where the rate is unknown (no failure seen at all)."""
    return FOUND_TARGETS[0] if rate is None or rate < RARE_BELOW else FOUND_TARGETS[1]


def found_verdict(vs: dict, target: float) -> str:
    """The verdict of one ratio of failures per run (module doc)."""
    if vs["ratio_low"] is not None and vs["ratio_low"] >= target:
        return REPRODUCES
    if vs["ratio_high"] is not None and vs["ratio_high"] < target:
        return AGAINST
    return NOT_SHOWN


def estimate_verdict(row: dict, uniform_failures: int) -> str:
    """The verdict of one strategy's failure-rate estimate (module doc); the bias is judged
    only where Uniform saw a failure (with none its pooled estimate 0 has no variance, and the
    bias interval would ignore Uniform's uncertainty)."""
    bias, ratio = row["bias_vs_uniform"], row["error_ratio"]
    if not all(isinstance(v, float) and math.isfinite(v) for v in (bias["low"], bias["high"])):
        return NOT_SHOWN  # no interval (a strategy left with one seed has no variance)
    if uniform_failures and (bias["low"] > 0 or bias["high"] < 0):
        return AGAINST
    if ratio["high"] is not None and ratio["high"] < ERROR_TARGET:
        return AGAINST
    return REPRODUCES if uniform_failures and ratio["low"] is not None and \
        ratio["low"] >= ERROR_TARGET else NOT_SHOWN


def found_checks(regimes: dict[str, dict]) -> list[dict]:
    out = []
    for regime, summary in regimes.items():
        rate = reference_rate(summary)
        target = found_target(rate)
        for name, f in summary["found"].items():
            if name == REFERENCE or "vs_reference" not in f:
                continue
            vs = f["vs_reference"]
            out.append({"regime": regime, "strategy": name, "metric": "failures per 100 runs",
                        "cell": vs["paired"], "ratio": vs["ratio"], "ratio_low": vs["ratio_low"],
                        "ratio_high": vs["ratio_high"], "target": target,
                        "reference_rate": rate, "verdict": found_verdict(vs, target)})
    return out


def estimate_checks(regimes: dict[str, dict]) -> list[dict]:
    out = []
    for regime, summary in regimes.items():
        seen = (summary["estimates"].get("reference") or {}).get("uniform_collisions", 0)
        for name, row in summary["estimates"].items():
            if name in (REFERENCE, "reference") or "bias_vs_uniform" not in row:
                continue
            out.append({"regime": regime, "strategy": name,
                        "metric": "relative error at equal budget",
                        "cell": row["paired_abs_error"], "bias": row["bias_vs_uniform"],
                        "error_ratio": row["error_ratio"], "target": ERROR_TARGET,
                        "verdict": estimate_verdict(row, seen)})
    return out


def learn_checks(regimes: dict[str, dict]) -> list[dict]:
    """One check per regime with a learning side and strategy beside Uniform (module doc)."""
    out = []
    for regime, summary in regimes.items():
        if not (learning := summary.get("learning")):
            continue
        failures = learning["sets"]["test"]["failures"]
        enough = failures >= learning["config"]["min_test_failures"]
        for name, row in learning["strategies"].items():
            if "vs_reference" not in row or name not in WEIGHTED:
                continue
            vs = row["vs_reference"]
            verdict = check_verdict(vs["area"], "better") if enough else NOT_SHOWN
            mde = vs["detectable"]["mde"]
            out.append({"regime": regime, "strategy": name, "metric": "area under Test AUPRC",
                        "cell": vs["area"], "mde": mde, "test_failures": failures,
                        "null_at_mde": bool(enough and verdict == NOT_SHOWN and mde is not None
                                            and mde <= NULL_MDE),
                        "verdict": AGAINST if verdict == REVERSED else verdict})
    return out


def _claim(id_: str, claim: str, checks: list[dict], regimes: int, ran: bool) -> dict:
    """A claim over the regimes (module doc; `ran`: a strategy it is about has curves)."""
    if not checks:
        return {"id": id_, "claim": claim, "checks": [], "verdict": NOT_SHOWN if ran else NOT_RUN}
    wins: dict[str, int] = {}
    for c in checks:
        wins[c["strategy"]] = wins.get(c["strategy"], 0) + (c["verdict"] == REPRODUCES)
    if max(wins.values()) >= regimes:
        verdict = REPRODUCES
    elif all(c["verdict"] == AGAINST for c in checks):
        verdict = AGAINST
    else:
        verdict = PARTLY if any(wins.values()) else NOT_SHOWN
    return {"id": id_, "claim": claim, "checks": checks, "verdict": verdict}


def rare_findings(results: dict) -> list[dict]:
    """The protocol's claims with their checks and verdicts, over `results["regimes"]`."""
    regimes = results["regimes"]
    ran = {name for summary in regimes.values() for name in summary["found"]} - {REFERENCE}
    return [
        _claim("rare-found", "A strategy finds ≥ 10× Uniform's failures per run where failures "
               "are ≈ 0.1 % (≥ 3× at ≈ 1 %)", found_checks(regimes), len(regimes), bool(ran)),
        _claim("rare-estimate", "Its failure-rate estimate is unbiased and has ≥ 3× smaller "
               "relative error at equal budget", estimate_checks(regimes), len(regimes),
               bool(ran & set(ESTIMATING))),
        _claim("rare-learn", "The importance-weighted monitor trained on its runs beats "
               "Uniform's on the area under the Test AUPRC curve", learn_checks(regimes),
               sum(bool(s.get("learning")) for s in regimes.values()),
               any(s.get("learning") for s in regimes.values())),
    ]


def advice(findings: list[dict]) -> dict[str, dict[str, str]]:
    """Per regime, which strategy to use to find failures and which to estimate the failure
    rate with, from the claims' checks alone: the strategy whose ratio to Uniform has a CI above
    1 (the largest, to find; the smallest error with a bias CI holding 0, to estimate), else
    Uniform — a strategy no check showed better is no reason to leave p. Where the learning side
    ran, also which strategy's runs to train a monitor on ("learn"): the one whose `rare-learn`
    check reproduces (the largest gain), else Uniform."""
    by_id = {f["id"]: f["checks"] for f in findings}

    def finds(c: dict) -> float | None:
        return c["ratio"] or math.inf if c["ratio_low"] is not None and c["ratio_low"] > 1 \
            else None

    def estimates(c: dict) -> float | None:
        ratio, bias = c["error_ratio"], c["bias"]
        unbiased = bias["low"] is not None and bias["low"] <= 0 <= bias["high"]
        return ratio["value"] or math.inf if unbiased and ratio["low"] is not None and \
            ratio["low"] > 1 else None

    def learns(c: dict) -> float | None:
        return c["cell"]["mean_diff"] if c["verdict"] == REPRODUCES else None

    regimes = {c["regime"]: {} for claim in ("rare-found", "rare-estimate")
               for c in by_id.get(claim, [])}
    for use, claim, score in (("find", "rare-found", finds),
                              ("estimate", "rare-estimate", estimates),
                              ("learn", "rare-learn", learns)):
        for regime, row in regimes.items():
            checks = [c for c in by_id.get(claim, []) if c["regime"] == regime]
            if use == "learn" and not checks:
                continue  # the learning side did not run on this regime
            shown = [(v, c["strategy"]) for c in checks if (v := score(c)) is not None]
            row[use] = max(shown)[1] if shown else REFERENCE
    return regimes


def merge_rare(runs: list[dict]) -> list[dict]:
    """Runs ({"path", "config", "findings", "regimes"}: a results JSON's `rare` part and its
    file) as protocols ({"paths", "config", "findings"}): runs of one protocol merged, their
    claims checked over every regime (module doc, `evoeye.results.merge`)."""
    return merge_runs(runs, RareConfig().to_dict(), rare_findings, RareMergeError,
                      noun="protocol", label="rare-failure ", free=("learn",))
