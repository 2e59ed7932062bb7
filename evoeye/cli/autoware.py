"""`evoeye import autoware` and `evoeye export autoware`: Autoware (ROS 2) bags in and out."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.errors import ExitCode, UserError
from evoeye.cli.monitor import RootOpt, export_app
from evoeye.cli.output import err, out
from evoeye.paths import DataRoot

import_app = typer.Typer(no_args_is_help=True,
                         help="Import another stack's recordings into the warehouse.")
app.add_typer(import_app, name="import")

MappingOpt = Annotated[Path | None, typer.Option(
    "--mapping", exists=True, dir_okay=False,
    help="TOML file overriding the default topics, vehicle and clock (docs/autoware.md).")]


def load_mapping_option(path: Path | None, base=None):  # noqa: ANN001, ANN202 - heavy types
    """The mapping a --mapping file gives over `base` (default: Autoware's); a bad file is a
    UserError."""
    from evoeye.sources.autoware.config import MappingError, load_mapping

    try:
        return load_mapping(path, base)
    except MappingError as exc:
        raise UserError(str(exc), "see docs/autoware.md, \"Mapping file\"") from exc


LogsArg = Annotated[list[Path] | None, typer.Argument(
    help="Run logs to export (default: every run under <root>/runs, or --scenario's).",
    exists=True, dir_okay=False)]
ScenarioOpt = Annotated[str | None, typer.Option(
    "--scenario", callback=scenario_check(recorded=True),
    help=scenario_help("Only this logical scenario's runs.", recorded=True))]
RatesOpt = Annotated[str, typer.Option(
    "--rates", help="realistic: the stack's rates (odometry 50 Hz, objects and planning 10 Hz, "
    "control 33 Hz); lossless: every topic at 20 Hz.")]


@import_app.command("autoware")
def import_autoware(
    paths: Annotated[list[Path], typer.Argument(
        help="rosbag2 bags: folders with metadata.yaml, .mcap or .db3 files, or folders of "
             "them.", exists=True)],
    root: RootOpt = None,
    mapping: MappingOpt = None,
    batch: Annotated[str, typer.Option("--batch", help="Batch the runs go in.")] = "autoware",
) -> None:
    """Import Autoware rosbag2 bags (MCAP or .db3) as runs: scored, replayed and queried like
    simulated ones; labelled only from a ground-truth topic in the bag.

    Exits 3 if any bag was refused (one line each: bag, topic, problem); the others go in.
    """
    from evoeye.sources.autoware.importer import import_bags

    data = DataRoot.resolve(root)
    report = import_bags(data, paths, mapping=load_mapping_option(mapping), batch=batch,
                         on_bag=reading)
    print_import(report, batch)


def reading(path: Path) -> None:
    """One line on stderr as each recording is read."""
    from rich.markup import escape

    err().print(f"reading {escape(str(path))}")


def print_import(report, batch: str) -> None:  # noqa: ANN001 - ImportReport, a heavy module
    """What an import did, one line each; exit 3 if any recording was refused."""
    from rich.markup import escape

    console = out()
    console.soft_wrap = True
    for note in report.notes:
        console.print(f"[yellow]note[/] {escape(note)}")
    ingested = sum(len(r.ingested) for r in report.ingest)
    skipped = sum(r.skipped for r in report.ingest)
    for sid, source in sorted(report.labels.items()):
        console.print(f"{sid}: labels from {escape(source)}")
    console.print(f"{len(report.labels)} recordings converted, {ingested} runs ingested, "
                  f"{skipped} already in the warehouse (batch {batch})")
    if report.failed:
        for line in report.failed:
            err().print(f"[red]refused[/] {escape(line)}")
        exit_with(ExitCode.PARTIAL)


@export_app.command("autoware")
def export_autoware(
    output: Annotated[Path, typer.Option("--out", help="Folder for the bags (one per run).")],
    logs: LogsArg = None,
    root: RootOpt = None,
    scenario: ScenarioOpt = None,
    rates: RatesOpt = "realistic",
    mapping: MappingOpt = None,
) -> None:
    """Write simulated runs as Autoware-typed rosbag2 MCAP bags (with their ground truth)."""
    from evoeye.sources.autoware.export import export_run

    logs = logs_to_export(logs, root, scenario, rates)
    output.mkdir(parents=True, exist_ok=True)
    chosen = load_mapping_option(mapping)
    for log in logs:
        bag = export_run(log, output, mapping=chosen, rates=rates)
        out().print(f"wrote {bag}")


def logs_to_export(logs: list[Path] | None, root: Path | None, scenario: str | None,
                   rates: str) -> list[Path]:
    """The run logs an export names (default: every run of the root, or the scenario's);
    UserError for unknown rates or no log."""
    from evoeye.sources.autoware.export import RATES
    from evoeye.store.ingest import discover_logs

    if rates not in RATES:
        raise UserError(f"--rates {rates!r} is not one of {sorted(RATES)}", "")
    if not logs:
        data = DataRoot.existing(root)
        logs = discover_logs(data.runs / scenario if scenario else data.runs)
    if not logs:
        raise UserError("no run log to export", "simulate some first: `evoeye simulate …`")
    return logs
