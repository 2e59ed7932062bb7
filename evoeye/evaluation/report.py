"""The evaluation report: Markdown and a self-contained HTML page, from evaluation dicts.

Everything renders from `EvaluationReport.to_dict()` (what `--json` prints), so the Markdown,
the HTML and the JSON cannot disagree. The conventions are docs/reports.md's: the headline
first (`evoeye.evaluation.headline`: collisions warned of, lead time, false alarms per hour,
each with its interval over runs), then the paper's RQ1 tables, narrow enough for the Prefect
artifact view; rates in % with one decimal, times in seconds.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from datetime import UTC, datetime
from html import escape
from pathlib import Path

from evoeye.evaluation.headline import headline_table, label, point_note, summary
from evoeye.evaluation.plots import line_chart, strip_chart
from evoeye.evaluation.table import (
    DASH,
    UNREACHABLE,
    UNREACHABLE_NOTE,
    Table,
    any_unreachable,
    pct,
    rate,
)
from evoeye.paths import DataRoot


def _short(fpr: str) -> str:
    """A target FPR as a column suffix: "0.05" → "@.05"."""
    return "@" + fpr.removeprefix("0")


def rq1_tables(report: dict) -> list[tuple[str, Table]]:
    """The paper's RQ1 figures of one logical scenario, one narrow table per level: per frame,
    then per run for each K (P / R / F1 at each target FPR's threshold, AUROC, AUPRC)."""
    fprs = [str(f) for f in report["fprs"]]
    header = ["Monitor"] + [f"{x}{_short(f)}" for f in fprs for x in ("P", "R", "F1")]
    header += ["AUROC", "AUPRC"]

    def row(m: dict, level: dict) -> list[str]:
        return ([label(m["name"])]
                + [rate(level["at_fpr"][f], x) for f in fprs for x in ("precision", "recall",
                                                                         "f1")]
                + [pct(level["auroc"]), pct(level["auprc"])])

    out = [("Per frame", Table(header, [row(m, m["frame"]) for m in report["monitors"]]))]
    for k in report["ks"]:
        warning = "1 alarm frame" if k == 1 else f"{k} consecutive alarm frames"
        out.append((f"Per run, a warning = {warning}",
                    Table(header, [row(m, m["scenario"][str(k)]) for m in report["monitors"]])))
    return out


def dataset_table(reports: list[dict]) -> Table:
    rows = []
    for r in reports:
        rows.append([r["logical_scenario"]])
        for split, s in r["dataset"].items():
            v = s["violations"] / s["scenarios"] if s["scenarios"] else None
            u = s["unsafe_frames"] / s["frames"] if s["frames"] else None
            rows.append([split, str(s["scenarios"]), f"{s['violations']} ({pct(v)} %)",
                         str(s["frames"]), f"{s['unsafe_frames']} ({pct(u)} %)"])
    return Table(["Split", "Runs", "Collisions", "Frames", "Unsafe frames"], rows)


def _calibrated(m: dict, fpr: str) -> list[str]:
    """Threshold and the FPR it realises on validation ('n/r' added if unreachable)."""
    realised = pct(m["val_fpr"].get(fpr))
    ok = m.get("reachable", {}).get(fpr, True)
    return [f"{m['thresholds'][fpr]:.4g}", realised if ok else f"{realised} {UNREACHABLE}"]


def monitors_table(reports: list[dict]) -> Table:
    """Versions, thresholds with the FPR they realise on validation (%), and CPU latency."""
    fprs = [str(f) for f in reports[0]["fprs"]] if reports else []
    header = ["Monitor", "Version", "L"]
    for f in fprs:
        header += [f"thr{_short(f)}", f"val FPR{_short(f)} %"]
    header += ["ms/frame"]
    rows = []
    for r in reports:
        rows.append([r["logical_scenario"]])
        for m in r["monitors"]:
            lat = m["latency"]
            rows.append([label(m["name"]), m["version"], str(m["context_len"])]
                        + [c for f in fprs for c in _calibrated(m, f)]
                        + [f"{lat['latency_ms_median']:.3f}" if lat else DASH])
    return Table(header, rows)


CAUSES = ("perception", "prediction", "planning", "control", "compound")


def attribution_table(rows: list[dict]) -> Table:
    """Root causes by `evoeye explain` (rows of view attribution_shares): per logical scenario
    and software version, the runs explained, each cause's share of them (%), and how many
    collisions the careful reference driver avoids."""
    groups: dict[tuple[str, str], dict] = {}
    for r in rows:
        g = groups.setdefault((r["logical_scenario"], r["software_version"]), dict(r))
        g[r["cause"]] = r["share"]
    out: list[list[str]] = []
    for (ls, version), g in groups.items():
        if not out or out[-1] != [ls]:
            out.append([ls])
        careful = g["careful_avoided"] / g["careful_runs"] if g["careful_runs"] else None
        out.append([version, str(g["runs"]), *(pct(g.get(c, 0.0)) for c in CAUSES),
                    f"{g['careful_avoided']}/{g['careful_runs']} ({pct(careful)} %)"])
    return Table(["ADS version", "Runs", *CAUSES, "Careful driver avoids"], out)


def _attribution_rows(reports: list[dict]) -> list[dict]:
    return [row for r in reports for row in r.get("attribution", [])]


ATTRIBUTION_NOTE = ("Collision runs re-simulated with one module replaced by an oracle; a "
                    "run's unit of credit is split among the oracles that avoid the collision, "
                    "'compound' when none does. Shares in %.")


TITLE = "Monitoring effectiveness (RQ1)"
DETAILS_NOTE = ("Rates in %. Every monitor's thresholds are calibrated on validation for each "
                "target FPR and applied unchanged to test; P / R / F1{at} are precision, "
                "recall and F1 at the threshold for that target FPR. Frames at or after a "
                "collision are not scored.")
HEADLINE_NOTE = ("Warned: collision runs warned of before the collision, of all. Lead: median "
                 "time from the warning to the collision. False al./h: warnings in "
                 "collision-free runs per hour of their driving. Safe runs al.: collision-free "
                 "runs with at least one warning. In parentheses: 95 % intervals over runs "
                 "(n = 1: one run, no interval; ≤: no false alarm, the upper bound).")


def _details_note(reports: list[dict]) -> str:
    fprs = [str(f) for f in reports[0]["fprs"]] if reports else []
    return DETAILS_NOTE.format(at=" " + ", ".join(_short(f) for f in fprs) if fprs else "")


def markdown_report(reports: list[dict]) -> str:
    """The headline per logical scenario, then the paper's RQ1 tables, the dataset, the
    monitors and the root causes."""
    parts = [f"# {TITLE}", "", point_note(reports), "", HEADLINE_NOTE, ""]
    if any_unreachable(reports):
        parts += [UNREACHABLE_NOTE, ""]
    for r in reports:
        parts += [f"## {r['logical_scenario']}", "", *summary(r), "",
                  headline_table(r).markdown(), ""]
    parts += ["## Details (paper Table \"Monitoring effectiveness\")", "",
              _details_note(reports), ""]
    for r in reports:
        for title, table in rq1_tables(r):
            parts += [f"### {r['logical_scenario']}: {title.lower()}", "", table.markdown(), ""]
    parts += ["## Dataset", "", dataset_table(reports).markdown(), "",
              "## Monitors", "", monitors_table(reports).markdown(), ""]
    if causes := _attribution_rows(reports):
        parts += ["## Root causes (evoeye explain)", "", ATTRIBUTION_NOTE, "",
                  attribution_table(causes).markdown(), ""]
    return "\n".join(parts)


CSS = """
body{font:14px/1.45 system-ui,sans-serif;margin:24px auto;max-width:1180px;color:#222}
h1{font-size:22px}h2{font-size:18px;margin-top:30px;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:8px 0 16px;font-size:13px}
th,td{border:1px solid #ddd;padding:3px 7px;text-align:right}
th:first-child,td:first-child{text-align:left}
tr.sec td{background:#f3f3f3;font-weight:600;text-align:left}
.charts{display:flex;flex-wrap:wrap;gap:12px}
svg.chart{font:11px sans-serif;background:#fafafa;border:1px solid #eee}
svg .t{font-size:13px;font-weight:600} svg .s{font-size:11px}
.note{color:#666;font-size:12px}
"""


def _charts(r: dict) -> str:
    ms = r["monitors"]
    roc = [(label(m["name"]), m["curves"]["roc_fpr"], m["curves"]["roc_tpr"]) for m in ms]
    pr = [(label(m["name"]), m["curves"]["pr_recall"], m["curves"]["pr_precision"]) for m in ms]
    charts = [
        line_chart(roc, title="ROC (test frames)", xlabel="false-positive rate",
                   ylabel="true-positive rate", diagonal=True),
        line_chart(pr, title="Precision-recall (test frames)", xlabel="recall",
                   ylabel="precision", legend_at="top-right"),
    ]
    for k in r["ks"]:
        for f in (str(x) for x in r["fprs"]):
            rows = [(label(m["name"]), m["scenario"][str(k)]["lead_time"][f]["values_s"])
                    for m in ms]
            charts.append(strip_chart(rows, title=f"Warning lead time, K={k}, FPR {f}",
                                      xlabel="lead time before the collision (s)"))
    return '<div class="charts">' + "".join(charts) + "</div>"


def _headline_html(r: dict) -> str:
    lines = "".join(f"<li>{escape(line.strip())}</li>" for line in summary(r)[1:])
    return (f"<h2>{escape(r['logical_scenario'])}</h2><p>{escape(summary(r)[0])}</p>"
            f"<ul>{lines}</ul>" + headline_table(r).html())


def html_report(reports: list[dict], title: str = f"evoeye: {TITLE}") -> str:
    """One self-contained HTML page: inline CSS and SVG, no scripts, no external resources."""
    stamp = f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC"
    body = [f"<h1>{escape(title)}</h1>",
            f'<p class="note">Generated {stamp}. {escape(point_note(reports))}</p>',
            f'<p class="note">{escape(HEADLINE_NOTE)}</p>']
    if any_unreachable(reports):
        body.append(f'<p class="note">{escape(UNREACHABLE_NOTE)}</p>')
    body += [_headline_html(r) for r in reports]
    body += ['<h2>Details (paper Table "Monitoring effectiveness")</h2>',
             f'<p class="note">{escape(_details_note(reports))}</p>']
    for r in reports:
        for name, table in rq1_tables(r):
            body += [f"<h3>{escape(r['logical_scenario'])}: {escape(name.lower())}</h3>",
                     table.html()]
        body.append(_charts(r))
    body += ["<h2>Dataset</h2>", dataset_table(reports).html(),
             "<h2>Monitors</h2>", monitors_table(reports).html()]
    if causes := _attribution_rows(reports):
        body += ["<h2>Root causes (evoeye explain)</h2>",
                 f'<p class="note">{escape(ATTRIBUTION_NOTE)}</p>',
                 attribution_table(causes).html()]
    return html_page(title, body)


def html_page(title: str, body: list[str]) -> str:
    """A self-contained HTML page of `body`'s elements: inline CSS, no scripts, nothing
    external."""
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{CSS}</style></head><body>"
            + "".join(body) + "</body></html>\n")


@dataclass(frozen=True)
class ReportFiles:
    folder: Path
    markdown: Path
    html: Path
    json: Path

    @classmethod
    def under(cls, root: DataRoot, name: str | None, prefix: str, markdown: str) -> ReportFiles:
        """The files of report `name` (default `<prefix>-<UTC time>`) in `<root>/reports/`,
        its folder made: `markdown`, report.html and report.json."""
        name = name or f"{prefix}-{datetime.now(UTC):%Y%m%dT%H%M%SZ}"
        if not name or "/" in name or name.startswith("."):
            raise ValueError(f"report name must be a plain folder name, got {name!r}")
        folder = root.path / "reports" / name
        folder.mkdir(parents=True, exist_ok=True)
        return cls(folder, folder / markdown, folder / "report.html", folder / "report.json")


def write_report(root: DataRoot, reports: list[dict],
                 name: str | None = None) -> ReportFiles:
    """Write rq1.md, report.html and report.json under `<root>/reports/<name>/`."""
    files = ReportFiles.under(root, name, "rq1", "rq1.md")
    name = files.folder.name
    files.markdown.write_text(markdown_report(reports), encoding="utf-8")
    files.html.write_text(html_report(reports, f"evoeye: {TITLE} — {name}"), encoding="utf-8")
    files.json.write_text(json.dumps(reports, indent=1) + "\n", encoding="utf-8")
    return files
