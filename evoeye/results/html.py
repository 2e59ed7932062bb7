"""The results as one self-contained HTML page: every table, and its CIs as error bars.

Per table: its rows and comparisons (the same cells as the Markdown), then for each set the
first metric and AUPRC as charts — each row's mean with its 95 % CI as an error bar, and each
comparison's mean paired difference with its bootstrap CI against a line at 0.
"""

from __future__ import annotations

from datetime import UTC, datetime
from html import escape

from evoeye.evaluation.plots import interval_chart
from evoeye.evaluation.report import CSS, Table
from evoeye.results.efficiency.report import efficiency_html
from evoeye.results.markdown import (
    FINDINGS_RULE,
    FLOOR_NOTE,
    METRIC_NAMES,
    UNPAIRED_NOTE,
    comparison_cells,
    comparison_intro,
    finding_checks,
    findings_summary,
    row_cells,
    table_intro,
)
from evoeye.results.rare.report import rare_html
from evoeye.results.tables import SET_NAMES, cell_key

CHART_METRICS = ("f1@0.05", "auprc")


def _pct(x: float | None) -> float | None:
    return None if x is None else 100 * x


def table_charts(table: dict) -> list[str]:
    """Error-bar charts of a table: per set, its first metric and AUPRC (where it has them)."""
    charts = []
    for s in table["sets"]:
        for m in [table["metrics"][0], *(k for k in CHART_METRICS[1:] if k in table["metrics"])]:
            key, what = cell_key(s, m), f"{SET_NAMES[s]} {METRIC_NAMES.get(m, m.upper())}"
            rows = [(r["method"], _pct(c["mean"]), _pct(c["low"]), _pct(c["high"]))
                    for r in table["rows"] for c in [r["cells"][key]]]
            charts.append(interval_chart(rows, title=f"{what}: mean, 95 % CI",
                                         xlabel=f"{what} (%)"))
            diffs = [(f"{c['a']} − {c['b']}", _pct(d["mean_diff"]), _pct(d["ci_low"]),
                      _pct(d["ci_high"])) for c in table["comparisons"] for d in [c["cells"][key]]]
            if diffs:
                charts.append(interval_chart(diffs, title=f"{what}: paired difference, 95 % CI",
                                             xlabel="a − b (points)", reference=0.0))
    return charts


def _table_html(table: dict) -> str:
    header, rows = row_cells(table)
    comp_header, comps = comparison_cells(table)
    parts = [f"<h3>{escape(table['scenario'])} — {escape(table['title'])}</h3>",
             f'<p class="note">{escape(table_intro(table))}</p>', Table(header, rows).html()]
    if any(r["unpaired"] for r in table["rows"]):
        parts.append(f'<p class="note">{escape(UNPAIRED_NOTE)}</p>')
    if comps:
        parts += [f'<p class="note">{escape(comparison_intro(table))}</p>',
                  Table(comp_header, comps).html()]
    return "".join(parts) + '<div class="charts">' + "".join(table_charts(table)) + "</div>"


def results_html(results: dict, title: str = "evoeye results") -> str:
    """One page: the findings, then every table with its charts (inline SVG, no scripts)."""
    stamp = f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC"
    body = [f"<h1>{escape(title)}</h1>",
            f'<p class="note">Generated {stamp}. {escape(FLOOR_NOTE)}</p>',
            "<h2>Findings</h2>", f'<p class="note">{escape(FINDINGS_RULE)}</p>',
            Table(*findings_summary(results["findings"])).html()]
    for f in results["findings"]:
        if f["checks"]:
            body += [f"<h3>{escape(f['claim'])}: {escape(f['verdict'])}</h3>",
                     Table(*finding_checks(f)).html()]
    for part, name in (("rq1", "Monitoring effectiveness (RQ1)"), ("ablation", "Monitor ablation"),
                       ("rq2", "Self-evolution under the same budget (RQ2)"),
                       ("evolution-ablation", "Evolution ablation"), ("aem-evo", "AEM-Evo"),
                       ("acquisition", "What each method acquired")):
        tables = [t for t in results["tables"] if t["id"] == part]
        if tables:
            body.append(f"<h2>{escape(name)}</h2>")
            body += [_table_html(t) for t in tables]
    if "efficiency" in results:
        body += efficiency_html(results["efficiency"])
    if "rare" in results:
        body += rare_html(results["rare"])
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{CSS}</style></head><body>"
            + "".join(body) + "</body></html>\n")
