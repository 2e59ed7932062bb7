"""What a flow run shows in the Prefect UI: a name that says what it does, and its result as a
Markdown artifact (in the form of docs/reports.md)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from evoeye.evaluation.table import Table, pct

if TYPE_CHECKING:
    from evoeye.batch import BatchSummary
    from evoeye.paths import DataRoot


def named(describe: Callable[[Any], str]) -> Callable[[], str]:
    """A `flow_run_name` callable: `describe(params)` of the running flow's `params`
    (`describe(None)` when it was called without)."""
    def name() -> str:
        from prefect.runtime import flow_run

        return describe(flow_run.parameters.get("params"))
    return name


def publish(key: str, markdown: str, description: str) -> None:
    """Publish a flow run's result as the Markdown artifact `key` (lower case and dashes)."""
    from prefect.artifacts import create_markdown_artifact

    create_markdown_artifact(markdown=markdown, key=key, description=description)


def batch_markdown(scenario: str, summary: BatchSummary, root: DataRoot) -> str:
    """A simulation batch: runs, collisions, failures, skipped, simulated time, wall time."""
    share = summary.collisions / summary.runs if summary.runs else None
    table = Table(["Runs", "Collisions", "Failed", "Skipped", "Simulated s", "Wall s"], [[
        str(summary.runs), f"{summary.collisions} ({pct(share)} %)", str(summary.failures),
        str(summary.skipped), f"{summary.simulated_s:.0f}", f"{summary.wall_s:.1f}"]])
    failed = [f"* {r.status} {r.scenario_id}: {r.reason}" for r in summary.results
              if r.status != "ok"]
    return "\n\n".join([f"# Simulated: {scenario}", table.markdown(), *failed,
                        f"Logs: `{root.runs / scenario}`"])


def ingest_markdown(report: dict[str, Any], root: DataRoot) -> str:
    """An ingest pass: runs and frames ingested, already in, quarantined (and why)."""
    table = Table(["Runs ingested", "Frames", "Already in", "Quarantined"], [[
        str(len(report["ingested"])), str(report["frames"]), str(report["skipped"]),
        str(len(report["quarantined"]))]])
    lines = [f"* quarantined `{log}`: {reason}" for log, reason in report["quarantined"]]
    if report.get("catalog_error"):
        lines.append(f"* views not refreshed: {report['catalog_error']}")
    return "\n\n".join(["# Ingested", table.markdown(), *lines,
                        f"Warehouse: `{root.warehouse}`"])


def train_markdown(version: str, card: dict[str, Any]) -> str:
    """A trained version: what it was trained on and its validation figures (%)."""
    val = card["metrics"]["val"]
    rows = []
    for fpr in sorted((float(f) for f in card["thresholds"]), reverse=True):
        m = val[f"fpr_{fpr:g}"]
        ok = m.get("reachable", True)
        rows.append([f"{fpr:g}", f"{m['threshold']:.4f}",
                     *([pct(m[k]) for k in ("precision", "recall", "f1")] if ok
                       else ["n/r"] * 3), pct(m["fpr"])])
    table = Table(["Target FPR", "Threshold", "P %", "R %", "F1 %", "FPR %"], rows)
    t = card["training"]
    return "\n".join([
        f"# Trained {version}", "",
        f"Logical scenario {card.get('logical_scenario')}, parent {card.get('parent') or 'none'}"
        f"; best epoch {t['best_epoch']} of {t['epochs_run']} ({t['time_s']:.0f} s).", "",
        f"On validation: AUROC {pct(val['auroc'])} %, AUPRC {pct(val['auprc'])} %.", "",
        table.markdown()])
