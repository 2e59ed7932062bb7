"""`evoeye import apollo` and `evoeye export apollo`: Apollo's cyber records in and out."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.autoware import (
    LogsArg,
    MappingOpt,
    RatesOpt,
    ScenarioOpt,
    import_app,
    load_mapping_option,
    logs_to_export,
    print_import,
    reading,
)
from evoeye.cli.monitor import RootOpt, export_app
from evoeye.cli.output import out
from evoeye.paths import DataRoot


@import_app.command("apollo")
def import_apollo(
    paths: Annotated[list[Path], typer.Argument(
        help="cyber records: .record files (split ones too), or folders of them.",
        exists=True)],
    root: RootOpt = None,
    mapping: MappingOpt = None,
    batch: Annotated[str, typer.Option("--batch", help="Batch the runs go in.")] = "apollo",
) -> None:
    """Import Apollo cyber records as runs: scored, replayed and queried like simulated ones;
    labelled only from a ground-truth channel in the record (docs/apollo.md).

    Exits 3 if any record was refused (one line each: record, channel, problem); the others
    go in.
    """
    from evoeye.sources.apollo.run import RECORDS, apollo_mapping
    from evoeye.sources.autoware.importer import import_bags

    chosen = load_mapping_option(mapping, apollo_mapping())
    report = import_bags(DataRoot.resolve(root), paths, mapping=chosen, batch=batch,
                         on_bag=reading, recordings=RECORDS)
    print_import(report, batch)


@export_app.command("apollo")
def export_apollo(
    output: Annotated[Path, typer.Option("--out", help="Folder for the records (one per run).")],
    logs: LogsArg = None,
    root: RootOpt = None,
    scenario: ScenarioOpt = None,
    rates: RatesOpt = "realistic",
) -> None:
    """Write simulated runs as Apollo cyber records (with their ground truth)."""
    from evoeye.sources.apollo.export import export_record

    for log in logs_to_export(logs, root, scenario, rates):
        out().print(f"wrote {export_record(log, output, rates=rates)}")
