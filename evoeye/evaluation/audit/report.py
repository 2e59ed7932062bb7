"""The audit report: `audit.md` for people, `audit.json` for scripts, under reports/."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import orjson

from evoeye.evaluation.audit.attribution import CAUSES, MODULES
from evoeye.evaluation.audit.context import ContextAuroc
from evoeye.evaluation.audit.runs import RunAudit
from evoeye.evaluation.audit.summary import ScenarioAudit
from evoeye.evaluation.audit.timing import ClockAuroc, histogram_lines
from evoeye.evaluation.audit.verdicts import NOT_EXPLAINED, NOT_INGESTED
from evoeye.paths import DataRoot

WORST_RUNS = 10  # runs listed per finding in the markdown (the JSON has every run)
KINEMATIC = (("a_lat", "lateral accel. m/s²"), ("a_lon", "longitudinal accel. m/s²"),
             ("lat_speed", "lateral speed m/s"))


def report_dir(root: DataRoot, scenario: str | None, batch: str | None) -> Path:
    """reports/audit-<scenario>-<batch>/ ("all" for what was not narrowed)."""
    return root.reports / f"audit-{scenario or 'all'}-{batch or 'all'}"


def report_dict(audits: list[ScenarioAudit], scenario: str | None, batch: str | None
                ) -> dict[str, Any]:
    return {"scenario": scenario, "batch": batch,
            "failed": any(a.failed for a in audits),
            "logical_scenarios": [a.to_dict() for a in audits]}


def _f(x: float | None, digits: int = 3) -> str:
    return "–" if x is None else f"{x:.{digits}f}"


def _kinematic_lines(s: ScenarioAudit) -> list[str]:
    out = ["| quantity (absolute) | runs over the bound | largest | run | actor | t s |",
           "|---|---|---|---|---|---|"]
    for name, label in KINEMATIC:
        runs = [r for r in s.runs if r.kinematics is not None]
        over = sum(name in r.kinematics.exceeded for r in runs)
        worst = max(runs, key=lambda r: getattr(r.kinematics, name).value, default=None)
        if worst is None:
            continue
        p = getattr(worst.kinematics, name)
        out.append(f"| {label} | {over} | {p.value:.2f} | {worst.scenario_id} | {p.actor_id} "
                   f"| {p.t_s:.2f} |")
    return out


def _worst_lines(runs: list[RunAudit]) -> list[str]:
    flagged = [r for r in runs if r.kinematics is not None and r.kinematics.violated]
    flagged.sort(key=lambda r: -r.kinematics.a_lat.value)
    out = ["| run | collided | lat. accel. (actor) | lon. accel. (actor) | lat. speed (actor) | "
           "pass-through pairs | pop-in |", "|---|---|---|---|---|---|---|"]
    for r in flagged[:WORST_RUNS]:
        k = r.kinematics
        cells = [f"{p.value:.1f} ({p.actor_id})" for p in (k.a_lat, k.a_lon, k.lat_speed)]
        out.append(f"| {r.scenario_id} | {'yes' if r.collided else 'no'} | {' | '.join(cells)} "
                   f"| {len(r.pass_through)} | {len(r.pop_in)} |")
    return out if flagged else []


def _other_findings(s: ScenarioAudit) -> list[str]:
    out = []
    for r in s.runs:
        for p in r.pass_through:
            out.append(f"* pass-through {r.scenario_id}: actors {p.actor_a} and {p.actor_b} "
                       f"overlap from t = {p.start_t_s:.2f} s for {p.duration_s:.2f} s")
        for a in r.pop_in:
            out.append(f"* pop-in {r.scenario_id}: actor {a.actor_id} appears at "
                       f"t = {a.t_s:.2f} s, {a.dist_m:.1f} m from the ego")
        if r.error:
            out.append(f"* unreadable {r.path}: {r.error}")
    shown = out[:2 * WORST_RUNS]
    if len(out) > len(shown):
        shown.append(f"* … {len(out) - len(shown)} more in audit.json")
    return shown


def _attribution_lines(s: ScenarioAudit) -> list[str]:
    a = s.attribution
    if a is None:
        return [NOT_EXPLAINED]
    head = "| | " + " | ".join(CAUSES) + " |"
    return [
        f"{a.explained_runs} of {a.collision_runs} collision runs explained; careful driver "
        f"avoids {_f(a.careful_avoidable)} (unavoidable {_f(a.careful_unavoidable)}) of "
        f"{a.careful_runs}.", "", head, "|---" * (len(CAUSES) + 1) + "|",
        "| credit share | " + " | ".join(f"{a.credit_share[c]:.3f}" for c in CAUSES) + " |",
        "| oracle avoids | " + " | ".join(f"{a.oracle_avoids[m]:.3f}" for m in MODULES) + " | |",
    ]


def _or_not_ingested(name: str, value: Any, line: Callable[[Any], str]) -> str:
    return f"{name}: {NOT_INGESTED}." if value is None else line(value)


def _clock_line(c: ClockAuroc) -> str:
    return (f"Clock-only AUROC on {c.frames:,} pre-collision frames ({c.unsafe_frames:,} "
            f"unsafe, {c.runs} runs): earlier = riskier {_f(c.earlier_riskier)}, best "
            f"direction {_f(c.best_direction)}, gradient boosting on t (out of fold, "
            f"grouped by run) {_f(c.model)}; headline **{_f(c.headline)}**.")


def _context_line(x: ContextAuroc) -> str:
    return (f"Context-only control (RQ1's: gradient boosting on t, the ego's speed and its x, "
            f"y; out of fold, grouped by run) on the same frames: AUROC **{_f(x.auroc)}**, "
            f"AUPRC {_f(x.auprc)}; without the ego's speed (when and where only, the script's "
            f"part) AUROC {_f(x.where_when_auroc)}, AUPRC {_f(x.where_when_auprc)}. A monitor "
            f"must beat the control's AUROC by 5 points (RQ1's bound); this batch trains it on "
            f"fewer runs than RQ1 does.")


def _timing_lines(s: ScenarioAudit) -> list[str]:
    out = []
    ct = s.collision_times
    if ct is None:
        out.append("No collisions.")
    else:
        q = ", ".join(f"{k} {v:.2f}" for k, v in ct.quantiles_s.items())
        out += [f"{ct.n} collisions; quantiles (s): {q}. Fullest {ct.bin_s:g} s bin: "
                f"{ct.top_bin_start_s:g}–{ct.top_bin_start_s + ct.bin_s:g} s with "
                f"{100 * ct.top_bin_share:.1f} %.", "", "```", *histogram_lines(ct), "```"]
    out += ["", _or_not_ingested("Clock-only AUROC", s.clock, _clock_line),
            "", _or_not_ingested("Context-only AUROC", s.context, _context_line)]
    return out


def markdown_report(audits: list[ScenarioAudit], scenario: str | None, batch: str | None) -> str:
    """The report as markdown: per logical scenario, verdicts first, then the details."""
    lines = [f"# Realism audit — scenario {scenario or 'all'}, batch {batch or 'all'}", ""]
    if not audits:
        lines.append("No run logs found.")
    for s in audits:
        lines += [f"## {s.logical_scenario}", "",
                  f"{len(s.runs)} runs ({s.ok_runs} ok, {s.unreadable_runs} unreadable), "
                  f"{s.collided_runs} collisions.", "",
                  "| criterion | value | bound | verdict |", "|---|---|---|---|"]
        lines += [f"| {v.criterion} | {v.value} | {v.bound} | {v.mark} |" for v in s.verdicts]
        lines += ["", "### Kinematics (NPCs, before the ego's first collision)", "",
                  *_kinematic_lines(s), "", *_worst_lines(s.runs), "",
                  "### Pass-through, pop-in", "", *(_other_findings(s) or ["None."]), "",
                  "### Collision times, the clock and the context", "", *_timing_lines(s), "",
                  "### Attribution (`evoeye explain`)", "", *_attribution_lines(s), ""]
    return "\n".join(lines)


def write_report(root: DataRoot, audits: list[ScenarioAudit], scenario: str | None,
                 batch: str | None) -> Path:
    """Write audit.md and audit.json; returns the folder."""
    out = report_dir(root, scenario, batch)
    out.mkdir(parents=True, exist_ok=True)
    (out / "audit.md").write_text(markdown_report(audits, scenario, batch), encoding="utf-8")
    (out / "audit.json").write_bytes(orjson.dumps(
        report_dict(audits, scenario, batch),
        option=orjson.OPT_INDENT_2 | orjson.OPT_SERIALIZE_NUMPY))
    return out
