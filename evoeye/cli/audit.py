"""`evoeye audit`: the realism report of a data root, one logical scenario or one batch."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.errors import ExitCode
from evoeye.cli.output import out, table
from evoeye.cli.simulate import RootOpt, plain_batch
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    from rich.table import Table

    from evoeye.evaluation.audit import ScenarioAudit


def summary_table(audits: list[ScenarioAudit]) -> Table:
    """One column per logical scenario, one row per criterion: value and verdict."""
    t = table("realism audit", ["criterion", "bound",
                                *(f"{s.logical_scenario} ({len(s.runs)} runs)" for s in audits)],
              left=("criterion", "bound"))
    colour = {True: "green", False: "red", None: "yellow"}
    for i, first in enumerate(audits[0].verdicts if audits else []):
        cells = [f"[{colour[s.verdicts[i].passed]}]{s.verdicts[i].mark}[/] {s.verdicts[i].value}"
                 for s in audits]
        t.add_row(first.criterion, first.bound, *cells)
    return t


@app.command("audit")
def audit_command(
    root: RootOpt = None,
    scenario: Annotated[str | None, typer.Option(
        callback=scenario_check(recorded=True),
        help=scenario_help("Only this logical scenario.", recorded=True))] = None,
    batch: Annotated[str | None, typer.Option(
        callback=plain_batch, help="Only this batch (e.g. demo, uniform-seed0).")] = None,
    workers: Annotated[int, typer.Option(min=1, help="Processes reading logs.")] = 1,
    as_json: Annotated[bool, typer.Option("--json", help="Print the report as JSON.")] = False,
    strict: Annotated[bool, typer.Option(
        help=f"Exit {int(ExitCode.CHECK_FAILED)} when a criterion fails.")] = False,
) -> None:
    """Check a batch's realism from its logs and the warehouse; write reports/audit-<S>-<B>/."""
    import orjson

    from evoeye.evaluation.audit import audit_root, write_report
    from evoeye.evaluation.audit.report import report_dict

    data = DataRoot.existing(root)
    audits = audit_root(data, scenario, batch, workers=workers)
    folder = write_report(data, audits, scenario, batch)
    if as_json:
        sys.stdout.write(orjson.dumps(report_dict(audits, scenario, batch),
                                      option=orjson.OPT_SERIALIZE_NUMPY).decode() + "\n")
    else:
        out().print(summary_table(audits))
        out().print(f"report: {folder / 'audit.md'}")
    if strict and any(s.failed for s in audits):
        exit_with(ExitCode.CHECK_FAILED)
