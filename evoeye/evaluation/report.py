"""The RQ1 report: Markdown tables and a self-contained HTML page, from evaluation dicts.

Everything renders from `EvaluationReport.to_dict()` (what `--json` prints), so the Markdown,
the HTML and the JSON cannot disagree. Rates are shown as percentages with one decimal, as in
the paper's Table "Monitoring effectiveness"; lead times in seconds.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from datetime import UTC, datetime
from html import escape
from pathlib import Path

from evoeye.evaluation.plots import line_chart, strip_chart
from evoeye.paths import DataRoot

DASH = "–"
UNREACHABLE = "n/r"  # the operating point's target FPR was unreachable on validation
UNREACHABLE_NOTE = ("n/r: the target FPR is unreachable for this monitor: more than that share "
                    "of the validation negatives tie at its top score, so no threshold meets "
                    "the target with any alarm (its rates there are not measured).")


def pct(x: float | None) -> str:
    """A rate as a percentage with one decimal ('–' if undefined)."""
    return DASH if x is None else f"{100 * x:.1f}"


def rate(point: dict, key: str) -> str:
    """A rate of one operating point (`PRF.to_dict()`) in %, 'n/r' where its target FPR was
    unreachable."""
    return pct(point[key]) if point.get("reachable", True) else UNREACHABLE


def any_unreachable(reports: list[dict]) -> bool:
    """Whether some monitor of these reports has a target FPR it could not reach."""
    return any(not ok for r in reports for m in r["monitors"]
               for ok in m.get("reachable", {}).values())


def secs(x: float | None) -> str:
    return DASH if x is None else f"{x:.2f}"


@dataclass
class Table:
    """Header and rows of text cells; section rows have a single cell."""

    header: list[str]
    rows: list[list[str]]

    def markdown(self) -> str:
        lines = ["| " + " | ".join(self.header) + " |",
                 "|" + "|".join(["---"] + ["---:"] * (len(self.header) - 1)) + "|"]
        for row in self.rows:
            cells = row if len(row) > 1 else [f"**{row[0]}**"] + [""] * (len(self.header) - 1)
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def html(self) -> str:
        head = "".join(f"<th>{escape(h)}</th>" for h in self.header)
        body = []
        for row in self.rows:
            if len(row) == 1:
                body.append(f'<tr class="sec"><td colspan="{len(self.header)}">'
                            f"{escape(row[0])}</td></tr>")
            else:
                body.append("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in row) + "</tr>")
        return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def rq1_table(report: dict) -> Table:
    """The paper's RQ1 table for one logical scenario (plus warned violations and lead time)."""
    fprs = [str(f) for f in report["fprs"]]
    main = fprs[0]
    header = ["Method"]
    for f in fprs:
        header += [f"P@{f}", f"R@{f}", f"F1@{f}"]
    header += ["AUROC", "AUPRC", f"Warned@{main}", f"Lead@{main} (s)"]
    rows: list[list[str]] = [["Frame-level"]]
    for m in report["monitors"]:
        fr = m["frame"]
        cells = [m["name"]]
        for f in fprs:
            cells += [rate(fr["at_fpr"][f], k) for k in ("precision", "recall", "f1")]
        rows.append(cells + [pct(fr["auroc"]), pct(fr["auprc"]), DASH, DASH])
    for k in report["ks"]:
        rows.append([f"Scenario-level (K={k})"])
        for m in report["monitors"]:
            sc = m["scenario"][str(k)]
            cells = [m["name"]]
            for f in fprs:
                cells += [rate(sc["at_fpr"][f], k) for k in ("precision", "recall", "f1")]
            lt = sc["lead_time"][main]
            warned = ([f"{lt['detected']}/{lt['violations']}", secs(lt["median_s"])]
                      if sc["at_fpr"][main].get("reachable", True) else [UNREACHABLE] * 2)
            cells += [pct(sc["auroc"]), pct(sc["auprc"]), *warned]
            rows.append(cells)
    return Table(header, rows)


def dataset_table(reports: list[dict]) -> Table:
    rows = []
    for r in reports:
        for split, s in r["dataset"].items():
            v = s["violations"] / s["scenarios"] if s["scenarios"] else None
            u = s["unsafe_frames"] / s["frames"] if s["frames"] else None
            rows.append([r["logical_scenario"], split, str(s["scenarios"]),
                         f"{s['violations']} ({pct(v)}%)", str(s["frames"]),
                         f"{s['unsafe_frames']} ({pct(u)}%)"])
    return Table(["Logical scenario", "Split", "Scenarios", "Violations", "Frames", "Unsafe"],
                 rows)


def _calibrated(m: dict, fpr: str) -> list[str]:
    """Threshold and the FPR it realises on validation ('n/r' added if unreachable)."""
    realised = pct(m["val_fpr"].get(fpr))
    ok = m.get("reachable", {}).get(fpr, True)
    return [f"{m['thresholds'][fpr]:.4g}", realised if ok else f"{realised} {UNREACHABLE}"]


def monitors_table(reports: list[dict]) -> Table:
    """Versions, thresholds with the FPR they realise on validation next to the target, and
    CPU cost."""
    fprs = [str(f) for f in reports[0]["fprs"]] if reports else []
    header = ["Logical scenario", "Method", "Version", "L"]
    for f in fprs:
        header += [f"thr@{f}", f"val FPR % (target {pct(float(f))})"]
    header += ["Latency b=1 (ms)", "Throughput b=1024 (/s)"]
    rows = []
    for r in reports:
        for m in r["monitors"]:
            lat = m["latency"]
            rows.append(
                [r["logical_scenario"], m["name"], m["version"], str(m["context_len"])]
                + [c for f in fprs for c in _calibrated(m, f)]
                + ([f"{lat['latency_ms_median']:.3f}", f"{lat['throughput_per_s']:,.0f}"]
                   if lat else [DASH, DASH])
            )
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
    out = []
    for (ls, version), g in groups.items():
        careful = g["careful_avoided"] / g["careful_runs"] if g["careful_runs"] else None
        out.append([ls, version, str(g["runs"]), *(pct(g.get(c, 0.0)) for c in CAUSES),
                    f"{g['careful_avoided']}/{g['careful_runs']} ({pct(careful)}%)"])
    return Table(["Logical scenario", "Version", "Runs", *CAUSES, "Careful driver avoids"], out)


def _attribution_rows(reports: list[dict]) -> list[dict]:
    return [row for r in reports for row in r.get("attribution", [])]


ATTRIBUTION_NOTE = ("Collision runs re-simulated with one module replaced by an oracle; a "
                    "run's unit of credit is split among the oracles that avoid the collision, "
                    "'compound' when none does. Shares in %.")


def markdown_report(reports: list[dict]) -> str:
    """RQ1 for every logical scenario evaluated, with the dataset and the monitors used."""
    parts = ["# RQ1: monitoring effectiveness", "",
             "Rates in %, thresholds calibrated on validation for each target FPR and applied "
             "unchanged to test. Warned: violation runs warned before the collision / all; "
             "Lead: median warning lead time of those runs.", ""]
    if any_unreachable(reports):
        parts += [UNREACHABLE_NOTE, ""]
    for r in reports:
        parts += [f"## {r['logical_scenario']}", "", rq1_table(r).markdown(), ""]
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


def _scenario_html(r: dict) -> str:
    ms = r["monitors"]
    roc = [(m["name"], m["curves"]["roc_fpr"], m["curves"]["roc_tpr"]) for m in ms]
    pr = [(m["name"], m["curves"]["pr_recall"], m["curves"]["pr_precision"]) for m in ms]
    charts = [
        line_chart(roc, title="ROC (test frames)", xlabel="false-positive rate",
                   ylabel="true-positive rate", diagonal=True),
        line_chart(pr, title="Precision-recall (test frames)", xlabel="recall",
                   ylabel="precision", legend_at="top-right"),
    ]
    for k in r["ks"]:
        for f in (str(x) for x in r["fprs"]):
            rows = [(m["name"], m["scenario"][str(k)]["lead_time"][f]["values_s"]) for m in ms]
            charts.append(strip_chart(rows, title=f"Warning lead time, K={k}, FPR {f}",
                                      xlabel="lead time before the collision (s)"))
    return (f"<h2>{escape(r['logical_scenario'])}</h2>" + rq1_table(r).html()
            + '<div class="charts">' + "".join(charts) + "</div>")


def html_report(reports: list[dict], title: str = "evoeye RQ1 report") -> str:
    """One self-contained HTML page: inline CSS and SVG, no scripts, no external resources."""
    stamp = f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC"
    body = [f"<h1>{escape(title)}</h1>",
            f'<p class="note">Generated {stamp}. Rates in %. Thresholds calibrated on '
            "validation frames, applied unchanged to test; frames at or after a collision are "
            "not scored. A run warns at its first K consecutive alarms before the collision.</p>"]
    if any_unreachable(reports):
        body.append(f'<p class="note">{escape(UNREACHABLE_NOTE)}</p>')
    body += [_scenario_html(r) for r in reports]
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
    files.html.write_text(html_report(reports, f"evoeye RQ1 report — {name}"), encoding="utf-8")
    files.json.write_text(json.dumps(reports, indent=1) + "\n", encoding="utf-8")
    return files
