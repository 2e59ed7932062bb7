"""What acquisition is for: the failures (collisions) each strategy's acquired runs held, per
run acquired, against Uniform's; and, from the strategies whose runs carry their exact p/q,
how well they estimate the failure rate under p (`failure_rates`).

A strategy's figure at a budget is Σ collisions / Σ runs acquired beyond the initial set over
the seeds (the initial runs are the same for every strategy and count for none), with a
percentile bootstrap interval resampling whole seeds (`rate_ci`). In generative mode every
acquired run is a run simulated; in pool mode it is one pre-simulated pool run, taken instead
of simulating one. The oracle and its control keep one increment of several they trained on,
so their runs acquired undercount what they looked at. Against Uniform: the ratio of the two
figures and the paired difference of the per-seed rates (`compare_paired`).
"""

from __future__ import annotations

import numpy as np

from evoeye.evaluation.failure_rate import failure_rate
from evoeye.evaluation.stats import compare_paired, rate_ci
from evoeye.results.efficiency.config import REFERENCE

PER = 100  # the figure is collisions per PER runs acquired


def _acquired(seeds: dict[str, dict], budget: int) -> dict[str, tuple[int, int]]:
    """{seed: (collisions, runs)} acquired by `budget`, for the seeds that acquired any."""
    out = {}
    for seed, curve in seeds.items():
        acq = curve["budgets"].get(str(budget), {}).get("acquired")
        if acq and acq["runs"]:
            out[seed] = (int(acq["collided"]), int(acq["runs"]))
    return out


def failures_found(curves: dict[str, dict[str, dict]], budget: int) -> dict[str, dict]:
    """Per strategy: {"seeds", "runs", "collisions", "per_run": rate_ci with its interval,
    and, beside Uniform, "vs_reference": {"ratio", "paired": compare_paired of per-seed rates}}
    at `budget` (module doc)."""
    acquired = {name: _acquired(seeds, budget) for name, seeds in curves.items()}
    out = {}
    for name, rows in acquired.items():
        if not rows:
            continue
        events, runs = zip(*rows.values(), strict=True)
        out[name] = {"seeds": len(rows), "runs": int(sum(runs)), "collisions": int(sum(events)),
                     "per_run": rate_ci(list(events), list(runs)).to_dict()}
    ref = acquired.get(REFERENCE)
    if not ref or REFERENCE not in out:
        return out
    for name, rows in acquired.items():
        common = [s for s in rows if s in ref]
        if name == REFERENCE or name not in out or len(common) < 2:
            continue
        mine = [rows[s][0] / rows[s][1] for s in common]
        theirs = [ref[s][0] / ref[s][1] for s in common]
        ref_rate = out[REFERENCE]["per_run"]["value"]
        out[name]["vs_reference"] = {
            "ratio": out[name]["per_run"]["value"] / ref_rate if ref_rate else None,
            "paired": compare_paired(mine, theirs).to_dict()}
    return out


def _estimates(seeds: dict[str, dict], budget: int, plain: bool) -> list[dict]:
    """Each seed's failure-rate estimate at `budget`: the importance-sampling one the curve
    stored (`acquired_summary`), or with `plain` (Uniform: its runs are drawn from p) plain
    Monte Carlo from its counts."""
    out = []
    for curve in seeds.values():
        acq = curve["budgets"].get(str(budget), {}).get("acquired")
        if not acq or not acq["runs"]:
            continue
        if "failure_rate" in acq:
            out.append(acq["failure_rate"])
        elif plain:
            hits = np.arange(acq["runs"]) < acq["collided"]
            out.append(failure_rate(hits, np.ones(acq["runs"])).to_dict())
    return out


def failure_rates(curves: dict[str, dict[str, dict]], budget: int) -> dict[str, dict]:
    """Per strategy with unbiased estimates of P_p(collision) at `budget` (Uniform's plain
    Monte Carlo, an importance-sampling strategy's weighted one): {"seeds", "mean" of the
    seeds' estimates, "spread": their SD over that mean (the relative error the seeds show),
    "relative_error": the median of the seeds' own SE / estimate (None where a seed found no
    failure), and beside Uniform "vs_reference": the ratio of both to Uniform's}."""
    out = {}
    for name, seeds in curves.items():
        rows = _estimates(seeds, budget, plain=name == REFERENCE)
        if not rows:
            continue
        values = np.array([r["value"] for r in rows], float)
        rel = [r["relative_error"] for r in rows if r["relative_error"] is not None]
        mean = float(values.mean())
        out[name] = {"seeds": len(rows), "mean": mean,
                     "spread": float(values.std(ddof=1) / mean) if len(rows) > 1 and mean
                     else None,
                     "relative_error": float(np.median(rel)) if len(rel) == len(rows) else None}
    ref = out.get(REFERENCE)
    for name, row in out.items():
        if name != REFERENCE and ref:
            row["vs_reference"] = {k: row[k] / ref[k] if row[k] and ref[k] else None
                                   for k in ("spread", "relative_error")}
    return out
