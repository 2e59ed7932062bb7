"""`evoeye audit`: the realism report of a data root, one logical scenario or one batch."""

from __future__ import annotations

import sys
from typing import Annotated

import orjson
import typer
from rich.console import Console
from rich.table import Table

from evoeye.cli.app import app
from evoeye.cli.simulate import RootOpt
from evoeye.evaluation.audit import ScenarioAudit, audit_root, write_report
from evoeye.evaluation.audit.report import report_dict
from evoeye.paths import DataRoot


def summary_table(audits: list[ScenarioAudit]) -> Table:
    """One column per logical scenario, one row per criterion: value and verdict."""
    table = Table(title="realism audit")
    table.add_column("criterion")
    table.add_column("bound")
    for s in audits:
        table.add_column(f"{s.logical_scenario} ({len(s.runs)} runs)")
    colour = {True: "green", False: "red", None: "yellow"}
    for i, first in enumerate(audits[0].verdicts if audits else []):
        cells = [f"[{colour[s.verdicts[i].passed]}]{s.verdicts[i].mark}[/] {s.verdicts[i].value}"
                 for s in audits]
        table.add_row(first.criterion, first.bound, *cells)
    return table


@app.command("audit")
def audit_command(
    root: RootOpt = None,
    scenario: Annotated[str | None, typer.Option(help="Only this logical scenario.")] = None,
    batch: Annotated[str | None, typer.Option(help="Only this batch.")] = None,
    workers: Annotated[int, typer.Option(min=1, help="Processes reading logs.")] = 1,
    as_json: Annotated[bool, typer.Option("--json", help="Print the report as JSON.")] = False,
    strict: Annotated[bool, typer.Option(help="Exit 1 when a criterion fails.")] = False,
) -> None:
    """Check a batch's realism from its logs and the warehouse; write reports/audit-<S>-<B>/."""
    data = DataRoot.resolve(root)
    audits = audit_root(data, scenario, batch, workers=workers)
    out = write_report(data, audits, scenario, batch)
    if as_json:
        sys.stdout.write(orjson.dumps(report_dict(audits, scenario, batch),
                                      option=orjson.OPT_SERIALIZE_NUMPY).decode() + "\n")
    else:
        console = Console()
        if not audits:
            console.print(f"no run logs under {data.runs}")
        else:
            console.print(summary_table(audits))
        console.print(f"report: {out / 'audit.md'}")
    if strict and any(s.failed for s in audits):
        raise typer.Exit(1)
