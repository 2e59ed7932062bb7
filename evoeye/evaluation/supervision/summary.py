"""The operating curves of a supervision: per trigger and threshold, what supervision prevents,
causes and costs, with paired bootstrap CIs; and every trigger at a false-intervention budget.

Per trigger and threshold, over the runs (each paired with its unsupervised run):

* collisions prevented: unsupervised collisions the supervised run does not have, as a share of
  the unsupervised collisions (a collision that only changes partner, e.g. to a car running
  into the braking ego from behind, is not prevented);
* collisions caused: supervised collisions of runs that had none (rear-end ones apart);
* false interventions per hour of safe driving: false interventions (`sweep`: unneeded — no
  collision within H, nor a critical approach — and changing the applied command) over the
  hours of the unsupervised runs' eligible frames where an intervention would not be justified,
  one denominator for every trigger; with an exact Poisson interval (Garwood) beside the
  bootstrap one, and per safe hazardous encounter (`criticality`);
* false alarms per hour, the earlier measure, beside it: every intervention at a frame labelled
  0, over the hours of eligible frames labelled 0;
* time in fallback per hour driven, the peak deceleration and the peak jerk of the runs that
  intervened (means over them), and the lead time of the first true intervention (median).

At a budget β the trigger runs at its threshold that prevents the most collisions with at most
β false interventions per hour (supervision off, preventing none, always meets it): the
collisions it prevents there (recall at a false-alarm budget), and at that threshold its false
interventions per hour and lead time. With `select` — the records of a supervision of other
runs (validation runs) under the same triggers and thresholds — that threshold is chosen on
them and only reported on these: no operating point is chosen on the runs it is reported on.
Without, it is chosen on these runs, and the summary says so (`operating_points`).

The oracle (`triggers.oracle_trigger`) is no trigger to choose: it is left out of the budgets
and the differences, and drawn as the ceiling — collisions prevented against its lead τ — and
each trigger at a budget is put beside it: the oracle's prevented share at the trigger's own
median lead (interpolated in τ, 0 at τ = 0), and the trigger's share of it.

CIs: 95 % percentile bootstrap over runs, B resamples (seeded). Every trigger's and threshold's
figures come from the same resamples — the comparison is paired run by run — computed at once
as products of the resampling counts with the per-run values; the operating point at a budget
is chosen again in every resample, so its CI includes the choice (the CIs of the false
interventions and the lead time at a budget are those of the threshold chosen on all runs).
Medians in a resample are weighted by the resampling counts. Each paired difference also
carries the exact McNemar p (`stats.paired_warnings_p`) of the two triggers' operating points:
which unsupervised collisions one prevents and the other does not. Percentile rather than BCa:
a choice among thresholds is no smooth statistic, and BCa's correction assumes one.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from evoeye.evaluation.mechanism import MECHANISMS
from evoeye.evaluation.stats import paired_warnings_p, poisson_ci
from evoeye.evaluation.supervision.settings import Settings
from evoeye.evaluation.supervision.triggers import ORACLE, TriggerSpec
from evoeye.monitor.families import DEFAULT_FAMILY

BUDGETS_PER_H = (0.5, 1.0, 2.0)
RESAMPLES = 4999
CONFIDENCE = 0.95
ROW_FIELDS = ("trigger", "threshold", "runs", "collisions_unsupervised", "collisions_prevented",
              "collisions_caused", "false_interventions_per_h", "false_alarms_per_h")


@dataclass(frozen=True)
class RunTable:
    """One trigger's per-run values, (R,) for the unsupervised run and (R, Θ) per threshold."""

    trigger: TriggerSpec
    collided0: np.ndarray  # (R,) bool
    safe_s: np.ndarray  # (R,) eligible seconds labelled 0 (false alarms' denominator)
    calm_s: np.ndarray  # (R,) eligible seconds where no intervention is justified
    encounters: np.ndarray  # (R,) safe hazardous encounters
    mechanism: np.ndarray  # (R,) object: the unsupervised collision's mechanism, None if safe
    collided: np.ndarray  # (R, Θ) bool
    rear_end: np.ndarray  # (R, Θ) bool: collided, struck from behind
    false: np.ndarray  # (R, Θ) false interventions
    false_alarms: np.ndarray  # (R, Θ) interventions at frames labelled 0
    interventions: np.ndarray  # (R, Θ)
    fallback_s: np.ndarray  # (R, Θ)
    duration_s: np.ndarray  # (R, Θ)
    decel_mps2: np.ndarray  # (R, Θ) peak, 0 without intervention
    jerk_mps3: np.ndarray  # (R, Θ)
    lead_s: np.ndarray  # (R, Θ) first true intervention's lead time, NaN if none

    @classmethod
    def of(cls, trigger: TriggerSpec, records: list[dict]) -> RunTable:
        n = len(trigger.thresholds)
        unsup = [r["unsupervised"] for r in records]
        cols: dict[str, list] = {k: [] for k in ("collided", "rear_end", "false", "alarms",
                                                 "interventions", "fallback_s", "duration_s",
                                                 "decel", "jerk", "lead")}
        if unsup and "calm_s" not in unsup[0]:
            raise ValueError("these records predate the false-intervention measure of "
                             "criticality.py: supervise the batch again")
        for r, u in zip(records, unsup, strict=True):
            t = r["triggers"][trigger.name]
            if len(t["sim_of"]) != n:
                raise ValueError(f"{r['scenario_id']}: {len(t['sim_of'])} thresholds recorded "
                                 f"for {trigger.name}, {n} expected")
            sims = [None if i is None else t["sims"][i] for i in t["sim_of"]]
            def col(key: str, default, sims=sims):  # noqa: ANN001, ANN202 - per threshold
                return [default if s is None else s[key] for s in sims]
            cols["collided"].append(col("collided", u["collided"]))
            rear = [s["collided"] and s["struck_from_behind"] if s else
                    u["collided"] and u["struck_from_behind"] for s in sims]
            cols["rear_end"].append(rear)
            cols["false"].append(col("false_interventions", 0))
            cols["alarms"].append(col("false_alarms", 0))
            cols["interventions"].append(col("interventions", 0))
            cols["fallback_s"].append(col("fallback_s", 0.0))
            cols["duration_s"].append(col("duration_s", u["duration_s"]))
            cols["decel"].append(col("peak_decel_mps2", 0.0))
            cols["jerk"].append(col("peak_jerk_mps3", 0.0))
            cols["lead"].append([np.nan if v is None else v for v in col("first_lead_s", None)])
        a = {k: np.array(v, dtype=float).reshape(len(records), n) for k, v in cols.items()}
        def per_run(key: str) -> np.ndarray:
            return np.array([u[key] for u in unsup], float)
        kinds = np.array([(u.get("mechanism") or {}).get("kind") for u in unsup], dtype=object)
        return cls(trigger, per_run("collided") > 0, per_run("safe_s"), per_run("calm_s"),
                   per_run("safe_encounters"), kinds, a["collided"] > 0, a["rear_end"] > 0,
                   a["false"], a["alarms"], a["interventions"], a["fallback_s"],
                   a["duration_s"], a["decel"], a["jerk"], a["lead"])

    @property
    def prevented(self) -> np.ndarray:  # (R, Θ)
        return self.collided0[:, None] & ~self.collided

    @property
    def caused(self) -> np.ndarray:  # (R, Θ)
        return ~self.collided0[:, None] & self.collided


def _ratio(num: np.ndarray, den: np.ndarray, scale: float = 1.0) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, scale * num / np.where(den > 0, den, 1.0), np.nan)


def _finite(x: float | np.ndarray) -> float | None:
    """A figure for JSON: None where undefined (no collision, no safe driving to divide by)."""
    return float(x) if np.isfinite(x) else None


def resampling_counts(n_runs: int, resamples: int = RESAMPLES, seed: int = 0) -> np.ndarray:
    """(B, R) how often each run is drawn in each bootstrap resample (seeded)."""
    rng = np.random.default_rng(seed)
    return rng.multinomial(n_runs, np.full(n_runs, 1.0 / n_runs), size=resamples).astype(float)


def at_budget(prevented: np.ndarray, fi_per_h: np.ndarray, budget: float) -> np.ndarray:
    """(…,) the largest prevented share among thresholds (last axis) with at most `budget`
    false interventions per hour; 0 (supervision off) if none meets it."""
    ok = fi_per_h <= budget + 1e-12
    return np.where(ok, np.nan_to_num(prevented, nan=0.0), 0.0).max(axis=-1, initial=0.0)


def _ci(samples: np.ndarray) -> list:
    """The percentile interval over axis 0: [low, high] for (B,) samples, one per column for
    (B, Θ); None where undefined (e.g. no unsupervised collision in any resample)."""
    lo_hi = [50 * (1 - CONFIDENCE), 50 * (1 + CONFIDENCE)]
    with warnings.catch_warnings():  # an all-NaN column is undefined, not an error
        warnings.simplefilter("ignore", RuntimeWarning)
        q = np.nanpercentile(samples, lo_hi, axis=0)  # (2,) or (2, Θ)
    pairs = [[None if not np.isfinite(v) else float(v) for v in col]
             for col in np.atleast_2d(q.T)]
    return pairs if samples.ndim > 1 else pairs[0]


def weighted_medians(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(B,) the (lower) median of the finite `values` (R,) in each resample (counts `weights`
    (B, R)); NaN in a resample that holds none of them."""
    keep = np.flatnonzero(np.isfinite(values))
    if keep.size == 0:
        return np.full(len(weights), np.nan)
    order = keep[np.argsort(values[keep], kind="stable")]
    cum = np.cumsum(weights[:, order], axis=1)  # (B, n)
    total = cum[:, -1:]
    idx = np.argmax(cum >= total / 2.0, axis=1)
    return np.where(total[:, 0] > 0, values[order][idx], np.nan)


def _mean_over(values: np.ndarray, where: np.ndarray) -> list[float | None]:
    """Per threshold, the mean of `values` (R, Θ) over the runs `where` (R, Θ) holds."""
    n = where.sum(axis=0)
    s = np.where(where, values, 0.0).sum(axis=0)
    return [float(v / k) if k else None for v, k in zip(s, n, strict=True)]


def trigger_points(table: RunTable, weights: np.ndarray) -> tuple[list[dict], np.ndarray,
                                                                  np.ndarray]:
    """The curve points of one trigger, and its resampled (B, Θ) prevented share and FI/h."""
    t = table.trigger
    c0, prevented, caused = table.collided0, table.prevented, table.caused
    calm_h, safe_h = table.calm_s.sum() / 3600.0, table.safe_s.sum() / 3600.0
    encounters = table.encounters.sum()
    p_share = _ratio(prevented.sum(axis=0), np.full(len(t.thresholds), c0.sum()))
    fi = _ratio(table.false.sum(axis=0), np.full(len(t.thresholds), calm_h))
    fa = _ratio(table.false_alarms.sum(axis=0), np.full(len(t.thresholds), safe_h))
    bp = _ratio(weights @ prevented, (weights @ c0)[:, None])  # (B, Θ)
    bf = _ratio(weights @ table.false, (weights @ table.calm_s)[:, None] / 3600.0)
    p_ci, f_ci = _ci(bp), _ci(bf)
    acted = table.interventions > 0
    kinds = sorted({k for k in table.mechanism if k is not None})
    once = np.ones((1, len(c0)))
    lead = [None if np.isnan(m := weighted_medians(col, once)[0]) else float(m)
            for col in table.lead_s.T]
    lead_ci = [_ci(weighted_medians(col, weights)) for col in table.lead_s.T]
    points = []
    for j, thr in enumerate(t.thresholds):
        points.append({
            "trigger": t.name, "label": t.label, "threshold": thr, "scale": t.scale,
            "target": t.targets[j], "val_fpr": t.val_fprs[j], "val_recall": t.val_recalls[j],
            "prevented_share": _finite(p_share[j]),
            "prevented_ci": p_ci[j], "false_interventions_per_h": _finite(fi[j]),
            "false_interventions_ci": f_ci[j],
            "false_interventions_poisson_ci": list(poisson_ci(int(table.false[:, j].sum()),
                                                              calm_h, CONFIDENCE)),
            "false_per_encounter": _finite(_ratio(table.false[:, j].sum(), encounters)),
            "false_alarms_per_h": _finite(fa[j]),
            "collisions_prevented": int(prevented[:, j].sum()),
            "collisions_caused": int(caused[:, j].sum()),
            "prevented_by_mechanism": {k: int((prevented[:, j] & (table.mechanism == k)).sum())
                                       for k in kinds},
            "caused_rear_end": int((caused[:, j] & table.rear_end[:, j]).sum()),
            "rear_end": int(table.rear_end[:, j].sum()),  # every supervised one hit from behind
            "interventions": int(table.interventions[:, j].sum()),
            "false_interventions": int(table.false[:, j].sum()),
            "fallback_s_per_h": _finite(_ratio(table.fallback_s[:, j].sum(),
                                               table.duration_s[:, j].sum() / 3600.0)),
            "peak_decel_mps2": _mean_over(table.decel_mps2, acted)[j],
            "peak_jerk_mps3": _mean_over(table.jerk_mps3, acted)[j],
            "lead_s": lead[j], "lead_ci": lead_ci[j],
        })
    return points, bp, bf


def _simulated(records: list[dict]) -> list[dict]:
    ok = [r for r in records if r["status"] == "ok"]
    if not ok:
        raise ValueError("no run of this supervision simulated: nothing to summarise")
    return ok


def oracle_curve(settings: Settings, points: list[dict]) -> list[dict]:
    """The oracle's prevented share (and CI) per lead τ, ascending; [] without an oracle."""
    oracle = next((t for t in settings.triggers if t.oracle), None)
    if oracle is None:
        return []
    mine = [p for p in points if p["trigger"] == oracle.name]  # in threshold order
    out = [{"lead_s": lead, "prevented_share": p["prevented_share"],
            "prevented_ci": p["prevented_ci"], "collisions_caused": p["collisions_caused"]}
           for lead, p in zip(oracle.leads_s, mine, strict=True)]
    return sorted(out, key=lambda o: o["lead_s"])


def oracle_share_at(ceiling: list[dict], lead_s: float | None) -> float | None:
    """The oracle's prevented share at a lead (linear in τ between its leads, 0 at τ = 0, its
    longest lead's beyond it); None without an oracle or a lead."""
    if not ceiling or lead_s is None:
        return None
    tau = [0.0] + [o["lead_s"] for o in ceiling]
    share = [0.0] + [o["prevented_share"] or 0.0 for o in ceiling]
    return float(np.interp(lead_s, tau, share))


def beside_oracle(ceiling: list[dict], point: dict) -> dict:
    """The oracle's share at the point's median lead, and the point's share of it."""
    at = oracle_share_at(ceiling, point["lead_s"])
    mine = point["prevented_share"] or 0.0
    return {"oracle_at_lead": at,
            "share_of_oracle": mine / at if at else None}


def _pairs(settings: Settings, names: list[str]) -> list[tuple[str, str]]:
    """The paired comparisons (a, b): the headline FusionMonitor against every other trigger,
    then each other trained trigger against every rule-based one (is it, too, ahead of them?)."""
    out = [(DEFAULT_FAMILY, n) for n in names if n != DEFAULT_FAMILY] if (
        DEFAULT_FAMILY in names) else []
    rules = [n for n in names if settings.trigger(n).rule_based]
    return out + [(a, r) for a in names if a != DEFAULT_FAMILY
                  and not settings.trigger(a).rule_based for r in rules]


def summarise_supervision(settings: Settings, records: list[dict],
                          budgets: tuple[float, ...] = BUDGETS_PER_H,
                          resamples: int = RESAMPLES, seed: int = 0,
                          select: list[dict] | None = None) -> dict:
    """The supervision's figures (module doc) as one JSON-serialisable dict; `rows` holds, per
    trigger and threshold, exactly ROW_FIELDS. `select`: the records operating points are
    chosen on (module doc)."""
    ok = _simulated(records)
    weights = resampling_counts(len(ok), resamples, seed)
    tables = [RunTable.of(t, ok) for t in settings.triggers]
    points, curves = [], {}
    for table in tables:
        pts, bp, bf = trigger_points(table, weights)
        points += pts
        if not table.trigger.oracle:
            curves[table.trigger.name] = (pts, bp, bf)
    sel = None if select is None else _simulated(select)
    picked = None if sel is None else {
        t.name: trigger_points(RunTable.of(t, sel), np.ones((1, len(sel))))[0]
        for t in settings.triggers if not t.oracle}
    ceiling = oracle_curve(settings, points)
    c0 = tables[0].collided0
    budget_rows, differences = [], []
    tables_by = {t.trigger.name: t for t in tables}
    for b in budgets:
        chosen, share, saved = {}, {}, {}
        for name, (pts, bp, bf) in curves.items():
            if picked is None:
                chosen[name] = at_budget(bp, bf, b)  # (B,)
                j = _operating_index(pts, b)
                best = _point_fields(None if j is None else pts[j])
            else:
                j = _operating_index(picked[name], b)
                chosen[name] = (np.zeros(len(bp)) if j is None
                                else np.nan_to_num(bp[:, j], nan=0.0))
                best = _point_fields(None if j is None else pts[j])
                best["val_false_interventions_per_h"] = (
                    0.0 if j is None else picked[name][j]["false_interventions_per_h"])
            share[name] = best["prevented_share"] or 0.0
            # (C,) which unsupervised collisions it prevents there: the paired test's data
            saved[name] = (np.zeros(int(c0.sum()), bool) if j is None
                           else tables_by[name].prevented[c0, j])
            budget_rows.append({"budget_per_h": b, "trigger": name,
                                "label": settings.trigger(name).label,
                                "prevented_ci": _ci(chosen[name]), **best,
                                **beside_oracle(ceiling, best)})
        for a, name in _pairs(settings, list(chosen)):
            differences.append({"budget_per_h": b, "a": a, "b": name,
                                "rule_based": settings.trigger(name).rule_based,
                                "difference": share[a] - share[name],
                                "ci": _ci(chosen[a] - chosen[name]),
                                "p": paired_warnings_p(saved[a], saved[name])})
    sims = sum(len(r["triggers"][t.name]["sims"]) for r in ok for t in settings.triggers)
    alarmed = sum(f is not None for r in ok for t in settings.triggers
                  for f in r["triggers"][t.name]["first_alarm_frame"])
    return {
        "scenario": settings.scenario, "batch": settings.batch, "runs": len(ok),
        "failed_runs": len(records) - len(ok),
        "collisions_unsupervised": int(c0.sum()),
        "safe_h": float(tables[0].calm_s.sum() / 3600.0),  # no intervention justified
        "label_safe_h": float(tables[0].safe_s.sum() / 3600.0),  # labelled 0 (false alarms')
        "safe_encounters": int(tables[0].encounters.sum()),
        "mechanisms": {k: int((tables[0].mechanism == k).sum())
                       for k in MECHANISMS if (tables[0].mechanism == k).any()},
        "rows": [dict(zip(ROW_FIELDS, (p["trigger"], p["threshold"], len(ok), int(c0.sum()),
                                       p["collisions_prevented"], p["collisions_caused"],
                                       p["false_interventions_per_h"], p["false_alarms_per_h"]),
                          strict=True))
                 for p in points if p["trigger"] != ORACLE],
        "points": points, "at_budget": budget_rows, "differences": differences,
        "oracle": ceiling, "operating_points": "test" if select is None else "validation",
        "selection_runs": None if sel is None else len(sel),
        "selection_safe_h": None if sel is None else float(  # what resolves a budget there
            sum(r["unsupervised"]["calm_s"] for r in sel) / 3600.0),
        "simulations": {"shared": sims + len(ok), "alarmed": alarmed + len(ok),
                        "naive": len(ok) * (1 + sum(len(t.thresholds) for t in settings.triggers))},
        "resamples": resamples, "confidence": CONFIDENCE, "budgets_per_h": list(budgets),
        "settings": settings.to_dict(),
    }


POINT_FIELDS = ("threshold", "scale", "prevented_share", "collisions_prevented",
                "false_interventions", "false_interventions_per_h",
                "false_interventions_ci", "false_interventions_poisson_ci", "false_alarms_per_h",
                "collisions_caused", "lead_s", "lead_ci", "prevented_by_mechanism")


def _operating_index(points: list[dict], budget: float) -> int | None:
    """The index of the threshold a trigger runs at within the budget (most prevented, then
    fewest false interventions), or None: supervision off."""
    ok = [j for j, p in enumerate(points) if p["false_interventions_per_h"] is not None
          and p["false_interventions_per_h"] <= budget + 1e-12]
    if not ok:
        return None
    return max(ok, key=lambda j: (points[j]["prevented_share"] or 0.0,
                                  -points[j]["false_interventions_per_h"]))


def _point_fields(p: dict | None) -> dict:
    """An operating point's figures; supervision off for None."""
    if p is None:
        return {"threshold": None, "scale": None, "prevented_share": 0.0,
                "collisions_prevented": 0, "false_interventions": 0,
                "false_interventions_per_h": 0.0,
                "false_interventions_ci": [0.0, 0.0], "false_interventions_poisson_ci": [0.0, 0.0],
                "false_alarms_per_h": 0.0, "collisions_caused": 0, "lead_s": None,
                "lead_ci": [None, None], "prevented_by_mechanism": {}}
    return {k: p[k] for k in POINT_FIELDS}
