"""`evoeye findings`: the paper's findings over several `evoeye results` runs."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app


@app.command("findings")
def findings_command(
    results: Annotated[list[Path], typer.Argument(
        help="results.json files (or report folders) of `evoeye results` runs.",
        metavar="RESULTS", show_default=False)],
    out: Annotated[Path | None, typer.Option(
        help="Write findings.md and findings.json here (e.g. docs/results).")] = None,
    readme: Annotated[Path | None, typer.Option(
        help="Also rewrite this README's findings section (between its markers).")] = None,
) -> None:
    """Check the paper's findings over several `evoeye results` runs — e.g. RQ1 and the monitor
    ablation on one data root, RQ2 and the evolution ablations on another — taking each table
    from the run that has it; a table two runs both have is refused."""
    from evoeye.results.combine import combine, write_combined

    typer.echo(write_combined(combine(results), out, readme))
