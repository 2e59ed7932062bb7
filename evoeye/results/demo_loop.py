"""The demo's closed-loop step: the shipped monitor judged where a user runs it, as the trigger of
a safety supervisor's fallback (docs/supervisor.md).

Per scenario, the shipped FusionMonitor and TTC-2D each trigger the default (production)
fallback — in-lane emergency braking at 9 m/s², reached at 30 m/s³ — on the demo's own runs,
each paired with its unsupervised run, beside the oracle that brakes τ s before each known
collision. The thresholds are a short sweep of the strict end (`FPRS`, `RECALLS`), calibrated
on the validation split's frames. Two supervisions, of the validation split's runs and of the
test split's (`SPLITS` of `evoeye.results.demo`): the first runs every threshold and chooses
each trigger's operating point at each budget (`BUDGETS_PER_H`); the second runs only the
chosen thresholds, and the oracle, on the test runs, where they are reported
(`summarise_supervision`'s `select`): no figure comes from a choice that saw its runs, and no
simulation is spent on a threshold no budget chose.

A budget of β false interventions per hour is *resolved* when the validation runs' hours of
driving where no intervention was justified allow at least one (β·h ≥ 1); below that every
budget means "none on the validation runs", and the words say so instead of naming β.
"""

from __future__ import annotations

from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path

from evoeye.evaluation.headline import MIN_COLLISIONS, label
from evoeye.evaluation.report import ReportFiles
from evoeye.evaluation.supervision.batch import (
    SupervisionResult,
    batch_runs,
    run_supervision,
    worker_pool,
)
from evoeye.evaluation.supervision.report import write_files
from evoeye.evaluation.supervision.settings import Settings
from evoeye.evaluation.supervision.summary import summarise_supervision
from evoeye.evaluation.supervision.triggers import (
    TriggerSpec,
    calibrate_triggers,
    oracle_trigger,
)
from evoeye.monitor.families import DEFAULT_FAMILY
from evoeye.paths import DataRoot
from evoeye.sim.supervisor import FallbackConfig
from evoeye.store import RunFilter, SplitSpec, Warehouse, select_runs
from evoeye.store.windows import DEFAULT_HORIZON_S

BUDGETS_PER_H = (1.0, 5.0)  # false interventions per hour of safe driving
BASELINE = "ttc-2d"  # the rule-based trigger beside the monitor
# four thresholds a trigger at most, from the strict end of the supervisor's sweep
# (`triggers.SWEEP_FPRS`, `RECALLS`; its looser ones brake tens of times an hour): every
# threshold and lead costs simulations, and the step must stay a small part of the demo
FPRS = (0.01, 0.001, 1e-4)
RECALLS = (0.05,)
ORACLE_LEADS_S = (0.5, 1.0, 1.5)  # from 1.5 s on it prevents nearly all (docs/supervisor.md)
REPORT_STEM = "supervision"  # supervision.md / .html / .json in the demo's report folder


def split_ids(root: DataRoot, scenario: str, batch: str, splits: SplitSpec
              ) -> dict[str, list[str]]:
    """The scenario ids of `batch`'s runs in the validation and the test split."""
    held = {spec.scenario_id for spec, _ in batch_runs(root, scenario, batch)}
    con = Warehouse(root).connect()
    try:
        return {split: sorted(held & set(select_runs(con, RunFilter(
                    scenario, split, splits=splits)).column("scenario_id").to_pylist()))
                for split in ("val", "test")}
    finally:
        con.close()


def supervise_demo(root: DataRoot, scenario: str, version: str, batch: str, splits: SplitSpec,
                   workers: int = 1) -> dict:
    """The closed-loop figures of `version` (the shipped monitor) and TTC-2D on `batch`'s test
    runs, every operating point chosen on its validation runs (module doc): the summary dict of
    `summarise_supervision`, with `errors` (runs that could not be supervised); or, when it
    cannot be measured, {"scenario", "skipped": why}."""
    ids = split_ids(root, scenario, batch, splits)
    if not ids["val"] or not ids["test"]:
        return {"scenario": scenario,
                "skipped": f"batch {batch} holds {_n(len(ids['val']), 'validation run')} and "
                           f"{_n(len(ids['test']), 'test run')}; it needs both"}
    triggers = calibrate_triggers(root, scenario, [("version", version), ("baseline", BASELINE)],
                                  splits, FPRS, recalls=RECALLS)
    # 1. every threshold on the validation runs (no oracle: it is no trigger to choose)
    choose = Settings(scenario, batch, tuple(triggers), FallbackConfig(), splits=splits,
                      logs="none")
    with nullcontext() if workers == 1 else worker_pool(workers) as pool:  # one for both
        val = run_supervision(root, choose, workers=workers, ids=ids["val"], pool=pool)
        if not any(r["status"] == "ok" for r in val.records):
            return _unmeasured(scenario, val)
        chosen = _chosen(choose, val.records)
        # 2. on the test runs only the thresholds chosen there, and the oracle
        report = Settings(scenario, batch, (*(narrowed(t, chosen[t.name]) for t in triggers),
                                            oracle_trigger(ORACLE_LEADS_S)),
                          FallbackConfig(), splits=splits, logs="none")
        test = run_supervision(root, report, workers=workers, ids=ids["test"], pool=pool)
    if not any(r["status"] == "ok" for r in test.records):
        return _unmeasured(scenario, test)
    summary = summarise_supervision(report, test.records, BUDGETS_PER_H,
                                    select=narrowed_records(val.records, triggers, chosen))
    summary["folder"], summary["selection_folder"] = str(test.folder), str(val.folder)
    summary["errors"] = [{"scenario_id": s, "reason": r} for s, r in val.errors + test.errors]
    return summary


def _unmeasured(scenario: str, done: SupervisionResult) -> dict:
    return {"scenario": scenario, "skipped": f"{_n(len(done.errors), 'run')} could not be "
            f"supervised, leaving a split without a run ({done.folder})"}


def _chosen(settings: Settings, records: list[dict]) -> dict[str, list[float]]:
    """Per trigger, the thresholds these (validation) runs choose at the budgets, ascending;
    its strictest if it stays off at every budget (a trigger needs one threshold)."""
    rows = summarise_supervision(settings, records, BUDGETS_PER_H, resamples=1)["at_budget"]
    return {t.name: sorted({r["threshold"] for r in rows if r["trigger"] == t.name
                            and r["threshold"] is not None} or {t.thresholds[-1]})
            for t in settings.triggers}


def narrowed(trigger: TriggerSpec, keep: list[float]) -> TriggerSpec:
    """The trigger at only the thresholds `keep` (a subset of its own, ascending)."""
    at = [trigger.thresholds.index(t) for t in keep]
    return replace(trigger, **{k: tuple(getattr(trigger, k)[j] for j in at) for k in
                               ("thresholds", "targets", "val_fprs", "val_recalls")})


def narrowed_records(records: list[dict], triggers: list[TriggerSpec],
                     keep: dict[str, list[float]]) -> list[dict]:
    """The runs' records as a supervision at only the thresholds `keep` would have them."""
    at = {t.name: [t.thresholds.index(x) for x in keep[t.name]] for t in triggers}
    out = []
    for r in records:
        if r["status"] != "ok":
            out.append(r)
            continue
        mine = {name: {**t, **{k: [t[k][j] for j in at[name]]
                               for k in ("sim_of", "first_alarm_frame")}}
                for name, t in r["triggers"].items() if name in at}
        out.append({**r, "triggers": mine})
    return out


def resolved(summary: dict, budget: float) -> bool:
    """Whether the validation runs' calm driving allows one false intervention within it."""
    return budget * (summary["selection_safe_h"] or 0.0) >= 1.0


def _n(count: float, noun: str) -> str:
    return f"{count:g} {noun}{'' if count == 1 else 's'}"


def _pct(share: float | None) -> str:
    return f"{100 * (share or 0.0):.0f} %"


def trigger_words(row: dict, collisions: int, calm_h: float) -> str:
    """What one trigger did at its operating point, its name left to the sentence: prevented /
    caused, false interventions, lead and the oracle at that lead."""
    prevented, caused = row["collisions_prevented"], row["collisions_caused"]
    ci = row["prevented_ci"] or [None, None]
    interval = ("" if None in ci else f" [95 % CI {100 * ci[0]:.0f}–{100 * ci[1]:.0f}]")
    net = ("caused none" if caused == 0 else
           f"caused {caused} (net {prevented - caused} of {collisions})")
    if row["threshold"] is None:
        return "stayed off: none of its thresholds stayed within that on the validation runs"
    did = (f"prevented {prevented} of {collisions} collisions "
           f"({_pct(row['prevented_share'])}{interval}) and {net}" if collisions else
           f"had no collision to prevent (no test run collided) and caused {caused}")
    rate = row["false_interventions_per_h"] or 0.0
    high = row["false_interventions_poisson_ci"][1]
    bound = "" if high is None else f", 95 % upper bound {high:.1f} / h"
    lead = ("with no timely warning" if row["lead_s"] is None else
            f"warning a median {row['lead_s']:.2f} s ahead — the oracle braking "
            f"{row['lead_s']:.2f} s ahead prevents {_pct(row['oracle_at_lead'])}")
    return (f"{did}, with {_n(row['false_interventions'], 'false intervention')} in "
            f"{calm_h:.2f} h of driving where none was justified ({rate:.1f} / h{bound}), "
            f"{lead}")


def _point(summary: dict, budgets: list[float]) -> str:
    """Where the operating point was chosen, in words, for these budgets."""
    sel, h = summary["selection_runs"], summary["selection_safe_h"] or 0.0
    if resolved(summary, budgets[0]):
        return (f"at the threshold chosen on the {sel} validation runs for ≤ "
                f"{_n(budgets[0], 'false intervention')} an hour")
    asked = " or ".join(f"≤ {b:g}" for b in budgets)
    why = (f"one false intervention is already {1 / h:.0f} an hour" if h > 0 else
           "they hold none of it")
    return (f"at the threshold chosen on the {sel} validation runs for no false intervention "
            f"there (their {h:.2f} h of driving where none was justified cannot resolve "
            f"{asked} an hour: {why})")


def _comparison(summary: dict, budget: float) -> str:
    d = next((d for d in summary["differences"] if d["budget_per_h"] == budget
              and d["a"] == DEFAULT_FAMILY and d["b"] == BASELINE), None)
    if d is None:
        return ""
    n = summary["collisions_unsupervised"]
    if n < MIN_COLLISIONS:
        return (f" {_n(n, 'test collision')}: too few to call either trigger better "
                f"(at least {MIN_COLLISIONS} needed).")
    ci = d["ci"]
    p = "" if d["p"] is None else f", exact McNemar p = {d['p']:.2g}"
    interval = "" if None in ci else f" [{100 * ci[0]:+.0f}, {100 * ci[1]:+.0f}]"
    return (f" Paired difference in collisions prevented, {label(DEFAULT_FAMILY)} − "
            f"{label(BASELINE)}: {100 * d['difference']:+.0f} points{interval}{p}.")


def loop_words(summary: dict) -> list[str]:
    """The scenario's closed-loop paragraph: a line per operating point (the budgets the
    validation runs cannot resolve share one, said so)."""
    if "skipped" in summary:
        return [f"  In the loop: not measured: {summary['skipped']}."]
    fb = summary["settings"]["fallback"]
    n, calm_h = summary["collisions_unsupervised"], summary["safe_h"]
    groups = [b for b in summary["budgets_per_h"] if not resolved(summary, b)]
    groups = ([groups] if groups else []) + [[b] for b in summary["budgets_per_h"]
                                            if resolved(summary, b)]
    lines = []
    for budgets in groups:
        rows = {r["trigger"]: r for r in summary["at_budget"]
                if r["budget_per_h"] == budgets[0]}
        text = (f"  In the loop: used as the trigger of a {fb['decel_mps2']:g} m/s² emergency "
                f"brake on the {summary['runs']} test runs, {_point(summary, budgets)}, the "
                f"{label(DEFAULT_FAMILY)} " + trigger_words(rows[DEFAULT_FAMILY], n, calm_h) + ".")
        if BASELINE in rows:
            text += (f" {label(BASELINE)}, its threshold chosen the same way, "
                     + trigger_words(rows[BASELINE], n, calm_h) + ".")
        lines.append(text + _comparison(summary, budgets[0]))
    if summary["errors"]:
        lines.append(f"  ({_n(len(summary['errors']), 'run')} could not be supervised and "
                     f"{'is' if len(summary['errors']) == 1 else 'are'} left out: "
                     f"{summary['folder']})")
    return lines


LOOP_NOTE = ("'In the loop' re-simulates this demo's test runs with each trigger driving the "
             "fallback, each run paired with its unsupervised self; a false intervention is a "
             "brake that changed the command where the unsupervised run neither collided "
             f"within {DEFAULT_HORIZON_S:g} s nor came critically close; the oracle brakes a "
             "fixed time before each known collision. Kept short for time: at most "
             f"{len(FPRS) + len(RECALLS)} thresholds a trigger on the validation runs (the "
             "strict end of the supervisor's sweep, calibrated on the validation frames), only "
             "the chosen ones on the test runs, the oracle at "
             + ", ".join(f"{t:g}" for t in ORACLE_LEADS_S) + " s; budgets: "
             + ", ".join(f"≤ {b:g}" for b in BUDGETS_PER_H) + " false interventions per hour "
             "(docs/supervisor.md, In the demo).")


def write_loop_report(folder: Path, summaries: list[dict]) -> ReportFiles:
    """supervision.md, .html and .json in the demo's report folder, the plain words first."""
    files = ReportFiles(folder, *(folder / f"{REPORT_STEM}.{ext}"
                                  for ext in ("md", "html", "json")))
    preface = tuple(f"{s['scenario']}: " + " ".join(line.strip() for line in loop_words(s))
                    for s in summaries) + (LOOP_NOTE,)
    measured = [s for s in summaries if "skipped" not in s]
    return write_files(files, measured, "evoeye demo — the monitor in the loop", preface)
