"""`evoeye findings` and `evoeye reproduce`: the paper's findings over several `evoeye results`
runs, and those runs again from the plan the findings record."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.output import StepBar


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


def _named_root(value: str) -> tuple[str, Path]:
    name, sep, path = value.partition("=")
    if not sep or not name or not path:
        raise typer.BadParameter(f"--root {value!r}: give NAME=PATH, NAME a run of the plan "
                                 "(its file's stem, e.g. rq2)")
    return name, Path(path)


@app.command("reproduce")
def reproduce_command(
    findings: Annotated[Path, typer.Argument(
        help="The findings.json `evoeye findings` wrote, or its folder.")] = Path("docs/results"),
    data: Annotated[Path, typer.Option(
        help="Each run's data root is <data>/<name> unless --root names one.")] =
        Path("evoeye-studies"),
    root: Annotated[list[str] | None, typer.Option(
        "--root", help="NAME=PATH: run NAME (e.g. rq2) on this data root (repeatable).")] =
        None,
    only: Annotated[list[str] | None, typer.Option(
        "--only", help="Re-run only this run of the plan (repeatable); the others' files are "
                       "combined as they are.")] = None,
    workers: Annotated[int | None, typer.Option(
        min=1, help="Processes per run (default: each run's recorded).")] = None,
    readme: Annotated[Path | None, typer.Option(
        help="Also rewrite this README's findings section (between its markers).")] = None,
) -> None:
    """Regenerate every table of a findings file (docs/results): re-run each `evoeye results`
    run it was combined from, with the config it records, write the run's JSON and Markdown back
    beside it, and combine them again. Resumable: a re-run does only what is not done yet."""
    from evoeye.results.reproduce import reproduce

    roots = dict(map(_named_root, root or []))
    with StepBar("reproduce") as bar:
        text = reproduce(findings, data, roots=roots, only=only or (), workers=workers,
                         readme=readme, progress=bar)
    typer.echo(text)
