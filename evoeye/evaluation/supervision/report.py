"""The supervision report: Markdown, a self-contained HTML page and JSON, from summary dicts.

Everything renders from `summarise_supervision`'s dicts (what `--json` prints), one per logical
scenario. Headline first: at a false-intervention budget, the collisions each trigger prevents,
the FusionMonitor against the best rule-based trigger with the paired CI of the difference and
the collisions it causes; then every trigger at each budget, the paired differences, and the
operating curves. Tables stay narrow (at most eight columns) for the Prefect artifact view.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime
from html import escape
from pathlib import Path

from evoeye.evaluation.plots import lead_chart, operating_chart, standalone
from evoeye.evaluation.report import DASH, ReportFiles, Table, html_page, pct
from evoeye.evaluation.supervision.triggers import ORACLE
from evoeye.monitor.families import DEFAULT_FAMILY
from evoeye.paths import DataRoot

HEADLINE_BUDGET_PER_H = 1.0
TERMS = ("Collisions prevented (scenario-level recall of the paper's RQ1, here closed loop): "
         "unsupervised collisions the supervised run does not have, net of none: collisions "
         "caused are counted apart. False interventions per hour of safe driving: fallback "
         "engagements that changed the applied command while the unsupervised run neither "
         "collided within H nor came critically close (ground-truth TTC < 1.5 s or a required "
         "deceleration > 4 m/s²), over the hours where no intervention was justified; the "
         "interval beside the bootstrap one is the exact Poisson one. False alarms per hour: the "
         "earlier measure — every engagement while the unsupervised run had no collision "
         "within H. Lead: median time from the first true intervention to the unsupervised "
         "collision. Oracle: a trigger that engages τ s before each known collision and never "
         "otherwise; '% of oracle' is the trigger's prevented share over the oracle's at the "
         "trigger's own median lead (above 100 % where its preventions come with leads longer "
         "than its median). Intervals: 95 % paired percentile bootstrap over runs.")


def ci(pair: list | None, scale: float = 100.0, signed: bool = False) -> str:
    """' [low, high]' in the given scale, or '' when undefined."""
    if not pair or pair[0] is None or pair[1] is None:
        return ""
    form = "+.1f" if signed else ".1f"
    return f" [{scale * pair[0]:{form}}, {scale * pair[1]:{form}}]"


def _rate(x: float | None) -> str:
    return DASH if x is None else f"{x:.2f}"


def _opt(x: float | None, form: str = ".1f") -> str:
    return DASH if x is None else f"{x:{form}}"


def _at(summary: dict, budget: float) -> list[dict]:
    return [r for r in summary["at_budget"] if r["budget_per_h"] == budget]


def headline_budget(summary: dict) -> float:
    """HEADLINE_BUDGET_PER_H if the summary has it, else its first budget."""
    budgets = summary["budgets_per_h"]
    return HEADLINE_BUDGET_PER_H if HEADLINE_BUDGET_PER_H in budgets else budgets[0]


def headline(summary: dict, budget: float | None = None) -> str:
    """One paragraph: the FusionMonitor against the best rule-based trigger at the budget
    (default `headline_budget`)."""
    budget = headline_budget(summary) if budget is None else budget
    rows = {r["trigger"]: r for r in _at(summary, budget)}
    head = (f"**{summary['scenario']}** ({summary['runs']} runs, "
            f"{summary['collisions_unsupervised']} unsupervised collisions, "
            f"{summary['safe_h']:.2f} h of safe driving): at ≤ {budget:g} false intervention "
            "per hour of safe driving, ")
    fusion = rows.get(DEFAULT_FAMILY)
    diffs = [d for d in summary["differences"] if d["budget_per_h"] == budget and d["rule_based"]
             and d["a"] == DEFAULT_FAMILY]
    if fusion is None or not diffs:
        best = max(rows.values(), key=lambda r: r["prevented_share"])
        return head + (f"{best['label']} prevents the most collisions: "
                       f"{pct(best['prevented_share'])} %{ci(best['prevented_ci'])}.")
    rival = min(diffs, key=lambda d: d["difference"])  # the best rule-based trigger
    r = rows[rival["b"]]
    verdict = ("more than" if (rival["ci"][0] or 0) > 0 else
               "fewer than" if (rival["ci"][1] or 0) < 0 else "no surely different share from")
    mcnemar = "" if rival.get("p") is None else f" (McNemar p = {rival['p']:.2g})"
    oracle = ("" if fusion.get("oracle_at_lead") is None else
              f" (at its median lead of {fusion['lead_s']:.2f} s the oracle prevents "
              f"{pct(fusion['oracle_at_lead'])} %)")
    return head + (
        f"the {fusion['label']} prevents {pct(fusion['prevented_share'])} %"
        f"{ci(fusion['prevented_ci'])} of them{oracle} and causes {fusion['collisions_caused']} "
        f"new ones; the best rule-based trigger, {r['label']}, prevents "
        f"{pct(r['prevented_share'])} %{ci(r['prevented_ci'])}. Paired difference "
        f"{100 * rival['difference']:+.1f} points{ci(rival['ci'], signed=True)}{mcnemar}: "
        f"{verdict} every rule-based trigger"
        + ("." if verdict != "more than" or all((d["ci"][0] or 0) > 0 for d in diffs)
           else " but not all of them (table below)."))


def budget_table(summary: dict, budget: float) -> Table:
    rows = [[r["label"], f"{pct(r['prevented_share'])}{ci(r['prevented_ci'])}",
             f"{_rate(r['false_interventions_per_h'])}"
             f"{ci(r.get('false_interventions_poisson_ci'), scale=1.0)}",
             _rate(r.get("false_alarms_per_h")),
             f"{_opt(r['lead_s'], '.2f')}{ci(r['lead_ci'], scale=1.0)}",
             _opt(None if r.get("share_of_oracle") is None else 100 * r["share_of_oracle"],
                  ".0f"),
             str(r["collisions_caused"]),
             _threshold(r)] for r in _at(summary, budget)]
    return Table(["Trigger", f"Prevented % at ≤ {budget:g}/h", "False int./h [Poisson]",
                  "False alarms/h", "Lead s", "% of oracle", "Caused", "Threshold"], rows)


def _threshold(r: dict) -> str:
    """A threshold as the trigger compares it: its score, or its logit (the FusionMonitor)."""
    if r["threshold"] is None:
        return "off"
    return f"{r['threshold']:.4g}" + (" (logit)" if r.get("scale") == "logit" else "")


def mechanism_table(summary: dict, budget: float) -> Table:
    """The unsupervised collisions by mechanism (`evaluation.mechanism`), and how many of each
    every trigger prevents at the budget."""
    rows_at = _at(summary, budget)
    rows = [[kind, str(n)] + [str(r.get("prevented_by_mechanism", {}).get(kind, 0))
                              for r in rows_at]
            for kind, n in summary.get("mechanisms", {}).items()]
    return Table(["Mechanism", "Collisions"] + [f"{r['label']} ≤ {budget:g}/h" for r in rows_at],
                 rows)


def oracle_table(summary: dict) -> Table:
    rows = [[f"{o['lead_s']:g}", f"{pct(o['prevented_share'])}{ci(o['prevented_ci'])}",
             str(o["collisions_caused"])] for o in summary.get("oracle", [])]
    return Table(["Oracle lead τ s", "Prevented % [CI]", "Caused"], rows)


def chosen_on(summary: dict) -> str:
    if summary.get("operating_points") == "validation":
        return (f"Each trigger's operating point at a budget was chosen on "
                f"{summary['selection_runs']} other supervised runs (validation) and is reported "
                "here as it is on these runs: its false interventions may exceed the budget."
                + _resolution(summary.get("selection_safe_h")))
    return ("Each trigger's operating point at a budget was chosen on these very runs (no "
            "selection batch was given): optimistic, since the choice saw the runs it is "
            "reported on.")


def _resolution(hours: float | None) -> str:
    """What the selection runs' calm hours resolve: one false intervention there per hour."""
    if hours is None:
        return ""
    if hours <= 0:
        return (" They hold no driving where no intervention was justified: every budget means "
                "none there.")
    return (f" Their {hours:.2f} h of driving where no intervention was justified make one false "
            f"intervention {1 / hours:.2g} per hour: a budget below that means none there.")


def _p(difference: dict) -> str:
    """' p 0.012': the exact McNemar p of a paired difference, if recorded."""
    p = difference.get("p")
    return "" if p is None else f" p {p:.2g}"


def differences_table(summary: dict, headline: bool = True) -> Table:
    """The headline FusionMonitor against every other trigger (`headline`), or each other
    trained trigger against every rule-based one."""
    budgets = summary["budgets_per_h"]
    diffs = [d for d in summary["differences"] if (d["a"] == DEFAULT_FAMILY) == headline]
    by = {(d["a"], d["b"], d["budget_per_h"]): d for d in diffs}
    pairs = list(dict.fromkeys((d["a"], d["b"]) for d in diffs))
    labels = {p["trigger"]: p["label"] for p in summary["points"]}
    rows = [[(labels[b] + ("" if by[a, b, budgets[0]]["rule_based"] else " (trained)"))
             if headline else f"{labels[a]} − {labels[b]}"]
            + [f"{100 * by[a, b, x]['difference']:+.1f}{ci(by[a, b, x]['ci'], signed=True)}"
               f"{_p(by[a, b, x])}" for x in budgets] for a, b in pairs]
    first = "FusionMonitor − trigger" if headline else "trained − rule-based trigger"
    return Table([first] + [f"≤ {b:g}/h, points" for b in budgets], rows)


def has_other_differences(summary: dict) -> bool:
    return any(d["a"] != DEFAULT_FAMILY for d in summary["differences"])


def curve_table(summary: dict, trigger: str) -> Table:
    rows = []
    for p in (p for p in summary["points"] if p["trigger"] == trigger):
        rows.append([f"{_threshold(p)} ({p['target']})",
                     f"{_rate(p['false_interventions_per_h'])}"
                     f"{ci(p['false_interventions_ci'], scale=1.0)}",
                     f"{pct(p['prevented_share'])}{ci(p['prevented_ci'])}",
                     f"{p['collisions_caused']} ({p['caused_rear_end']})",
                     _opt(p["fallback_s_per_h"], ".0f"), _opt(p["peak_decel_mps2"]),
                     _opt(p["peak_jerk_mps3"], ".0f"),
                     f"{_opt(p['lead_s'], '.2f')}{ci(p['lead_ci'], scale=1.0)}"])
    return Table(["Threshold (val target)", "False int./h [CI]", "Prevented % [CI]",
                  "Caused (rear-end)", "Fallback s/h", "Decel m/s²", "Jerk m/s³", "Lead s"], rows)


def _setup(summary: dict) -> str:
    s = summary["settings"]
    fb, sims = s["fallback"], summary["simulations"]
    skipped = summary.get("skipped_runs", 0)
    after = f" (its runs after the first {skipped})" if skipped else ""
    return (f"Batch `{summary['batch']}`{after}, each run paired with its unsupervised run; "
            f"{summary.get('safe_encounters', 0)} safe hazardous encounters; alarm at "
            f"K = {s['consecutive']} frame(s) above the threshold; fallback: braking ramped at "
            f"{fb['jerk_mps3']:g} m/s³ to {fb['decel_mps2']:g} m/s² after {fb['onset_s']:g} s, "
            f"released after {fb['hold_s']:g} s at or below the threshold; H = "
            f"{s['horizon_s']:g} s; software {s['software_version']}. Simulations: "
            f"{sims['shared']} (every threshold alone: {sims['naive']}; only those with an "
            f"alarm: {sims['alarmed']}).")


def _triggers(summary: dict) -> list[tuple[str, str]]:
    return list(dict.fromkeys((p["trigger"], p["label"]) for p in summary["points"]))


def markdown_report(summaries: list[dict], figures: dict[str, str] | None = None,
                    preface: tuple[str, ...] = ()) -> str:
    """Every scenario's supervision; `figures` maps a scenario to its curve figure's file;
    `preface`: paragraphs before the headlines (e.g. the demo's plain words)."""
    parts = ["# Monitor in the loop: the supervisor's operating curves", ""]
    parts += [line for p in preface for line in (p, "")]
    parts += [line for s in summaries for line in (headline(s), "")] + [TERMS, ""]
    for s in summaries:
        parts += [f"## {s['scenario']}", "", _setup(s), "", chosen_on(s), ""]
        for b in s["budgets_per_h"]:
            parts += [budget_table(s, b).markdown(), ""]
        if s.get("mechanisms"):
            parts += ["What collides, by mechanism (`evaluation/mechanism.py`), and what each "
                      f"trigger prevents of it at ≤ {headline_budget(s):g} per hour:", "",
                      mechanism_table(s, headline_budget(s)).markdown(), ""]
        if s.get("oracle"):
            parts += ["The ceiling: the oracle engaging τ s before each known collision.", "",
                      oracle_table(s).markdown(), ""]
        if s["differences"]:
            parts += ["Paired differences in collisions prevented (FusionMonitor − trigger), "
                      "points [95 % CI]:", "", differences_table(s).markdown(), ""]
        if has_other_differences(s):
            parts += ["Each other trained trigger against the rule-based ones, points [95 % CI]:",
                      "", differences_table(s, headline=False).markdown(), ""]
        if figures and s["scenario"] in figures:
            parts += [f"![operating curves, {s['scenario']}]({figures[s['scenario']]})", ""]
        if figures and f"{s['scenario']}/lead" in figures:
            parts += [f"![prevented against lead, beside the oracle, {s['scenario']}]"
                      f"({figures[s['scenario'] + '/lead']})", ""]
        for name, label in _triggers(s):
            parts += [f"### {label}: operating curve", "", curve_table(s, name).markdown(), ""]
    return "\n".join(parts)


def _series(summary: dict) -> list[tuple[str, list[dict]]]:
    return [(label, [p for p in summary["points"] if p["trigger"] == name])
            for name, label in _triggers(summary) if name != ORACLE]


def curve_svg(summary: dict) -> str:
    return operating_chart(_series(summary), title=f"Operating curves, {summary['scenario']}",
                           budget=headline_budget(summary))


def lead_svg(summary: dict) -> str:
    return lead_chart(summary.get("oracle", []), _series(summary),
                      title=f"Prevented against lead, beside the oracle, {summary['scenario']}")


def html_report(summaries: list[dict], title: str = "evoeye supervision report",
                preface: tuple[str, ...] = ()) -> str:
    """One self-contained HTML page: inline CSS and SVG, no scripts, no external resources."""
    stamp = f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC"
    body = [f"<h1>{escape(title)}</h1>", f'<p class="note">Generated {stamp}.</p>']
    body += [f"<p>{escape(p)}</p>" for p in preface]
    body += [f"<p>{escape(headline(s)).replace('**', '')}</p>" for s in summaries]
    body.append(f'<p class="note">{escape(TERMS)}</p>')
    for s in summaries:
        body += [f"<h2>{escape(s['scenario'])}</h2>", f'<p class="note">{escape(_setup(s))}</p>',
                 f'<p class="note">{escape(chosen_on(s))}</p>',
                 f'<div class="charts">{curve_svg(s)}{lead_svg(s)}</div>']
        body += [budget_table(s, b).html() for b in s["budgets_per_h"]]
        if s.get("mechanisms"):
            body.append(mechanism_table(s, headline_budget(s)).html())
        if s.get("oracle"):
            body.append(oracle_table(s).html())
        if s["differences"]:
            body.append(differences_table(s).html())
        if has_other_differences(s):
            body.append(differences_table(s, headline=False).html())
        for name, label in _triggers(s):
            body += [f"<h3>{escape(label)}</h3>", curve_table(s, name).html()]
    return html_page(title, body)


def write_report(root: DataRoot, summaries: list[dict], name: str | None = None) -> ReportFiles:
    """supervision.md, report.html and report.json under `<root>/reports/<name>/`."""
    files = ReportFiles.under(root, name, "supervision", "supervision.md")
    return write_files(files, summaries, f"evoeye supervision — {files.folder.name}")


def write_files(files: ReportFiles, summaries: list[dict], title: str,
                preface: tuple[str, ...] = ()) -> ReportFiles:
    """The report's Markdown, HTML and JSON as `files` names them (`preface`: paragraphs before
    the headlines, in both pages)."""
    files.markdown.write_text(markdown_report(summaries, preface=preface), encoding="utf-8")
    files.html.write_text(html_report(summaries, title, preface), encoding="utf-8")
    files.json.write_text(json.dumps(summaries, indent=1) + "\n", encoding="utf-8")
    return files


def write_docs(folder: Path, summary: dict) -> list[Path]:
    """supervision-<scenario>.md (linking its .svg curves) and .json in `folder` (docs/results)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"supervision-{summary['scenario']}"
    svg, lead, md, js = (folder / f"{stem}{ext}" for ext in (".svg", "-lead.svg", ".md",
                                                             ".json"))
    svg.write_text(standalone(curve_svg(summary)), encoding="utf-8")
    lead.write_text(standalone(lead_svg(summary)), encoding="utf-8")
    md.write_text(markdown_report([summary], {summary["scenario"]: svg.name,
                                              f"{summary['scenario']}/lead": lead.name}),
                  encoding="utf-8")
    js.write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    return [md, svg, lead, js]
