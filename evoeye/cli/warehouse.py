"""`evoeye ingest`, `evoeye sql` and `evoeye warehouse stats`: the warehouse from the shell."""

from __future__ import annotations

import csv
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import duckdb
import orjson
import pyarrow as pa
import typer
from rich.console import Console
from rich.table import Table

from evoeye.cli.app import app
from evoeye.evaluation import report
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse, WarehouseLockedError
from evoeye.store.ingest import DEFAULT_RUNS_PER_PART, IngestReport, ingest


def _out() -> Console:
    """A console sized at call time (so COLUMNS set by the caller applies)."""
    return Console()


def _err() -> Console:
    return Console(stderr=True)

warehouse_app = typer.Typer(no_args_is_help=True, help="Inspect the Parquet/DuckDB warehouse.")
app.add_typer(warehouse_app, name="warehouse")

RootOpt = Annotated[
    Path | None,
    typer.Option("--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data)."),
]


class Format(StrEnum):
    table = "table"
    csv = "csv"
    json = "json"


def report_table(report: IngestReport) -> Table:
    table = Table(title="ingest", show_header=False)
    table.add_column(justify="left")
    table.add_column(justify="right")
    table.add_row("runs ingested", str(len(report.ingested)))
    table.add_row("frames ingested", f"{report.frames:,}")
    table.add_row("already in the warehouse", str(report.skipped))
    table.add_row("duplicate scenario ids", str(len(report.duplicates)))
    table.add_row("quarantined", str(len(report.quarantined)))
    table.add_row("parts of a killed ingest removed", str(len(report.orphans_removed)))
    return table


@app.command("ingest")
def ingest_command(
    root: RootOpt = None,
    runs_per_part: Annotated[
        int, typer.Option(min=1, help="Runs per Parquet part file.")
    ] = DEFAULT_RUNS_PER_PART,
) -> None:
    """Append every run log under <root>/runs not yet ingested to the warehouse."""
    data = DataRoot.resolve(root)
    try:
        with _out().status("ingesting…") as status:
            report = ingest(data, runs_per_part=runs_per_part,
                            on_log=lambda p: status.update(f"ingesting {p.name}"))
    except WarehouseLockedError as exc:
        _err().print(f"[red]error:[/] {exc}")
        raise typer.Exit(1) from exc
    _out().print(report_table(report))
    for log, reason in report.quarantined:
        _out().print(f"[yellow]quarantined[/] {log}: {reason}")
    for log in report.duplicates:
        _out().print(f"[yellow]duplicate[/] {log}: its scenario id is already ingested")
    if report.catalog_error:
        _out().print(f"[yellow]warning:[/] views not refreshed ({report.catalog_error}); "
                      "the data is in, the next ingest refreshes them")
    _out().print(f"warehouse: {data.warehouse}  (DuckDB: {data.duckdb_file})")


def _cell(value: Any, max_items: int = 4) -> str:
    if value is None:
        return "∅"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        head = ", ".join(_cell(v, max_items) for v in value[:max_items])
        more = f", … ({len(value)})" if len(value) > max_items else ""
        return f"[{head}{more}]"
    return str(value)


def print_table(result: pa.Table, max_rows: int) -> None:
    table = Table()
    for name in result.column_names:
        table.add_column(name, overflow="fold")
    for row in result.slice(0, max_rows).to_pylist():
        table.add_row(*(_cell(v) for v in row.values()))
    _out().print(table)
    if result.num_rows > max_rows:
        _out().print(f"… {result.num_rows - max_rows} more rows (--max-rows, or --format csv)")


def _csv_cell(value: Any) -> Any:
    return orjson.dumps(value, default=str).decode() if isinstance(value, list | dict) else value


def write_csv(result: pa.Table) -> None:
    out = csv.writer(sys.stdout, lineterminator="\n")
    out.writerow(result.column_names)
    for row in result.to_pylist():
        out.writerow([_csv_cell(v) for v in row.values()])


def write_json(result: pa.Table) -> None:
    sys.stdout.write(orjson.dumps(result.to_pylist(), default=str,
                                  option=orjson.OPT_SERIALIZE_NUMPY).decode() + "\n")


@app.command("sql")
def sql_command(
    query: Annotated[str, typer.Argument(help="SQL over the warehouse views, e.g. "
                                             "\"SELECT * FROM dataset_stats\".")],
    root: RootOpt = None,
    fmt: Annotated[Format, typer.Option("--format", help="Output format.")] = Format.table,
    max_rows: Annotated[int, typer.Option(min=1, help="Rows shown in table format.")] = 50,
) -> None:
    """Run a SQL query against the warehouse (read-only: reads the Parquet directly)."""
    try:
        result = Warehouse(root).sql(query)
    except duckdb.Error as exc:
        _err().print(f"[red]error:[/] {exc}")
        raise typer.Exit(1) from exc
    if fmt is Format.csv:
        write_csv(result)
    elif fmt is Format.json:
        write_json(result)
    else:
        print_table(result, max_rows)


def _count_pct(count: int, pct: float | None) -> str:
    return f"{count:,} ({pct:.1f}%)" if pct is not None else f"{count:,}"


def attribution_table(rows: list[dict[str, Any]]) -> Table:
    """Root causes by `evoeye explain` (rows of view attribution_shares) as a console table."""
    shares = report.attribution_table(rows)
    table = Table(title="root causes of collisions (evoeye explain), %")
    for i, col in enumerate(shares.header):
        table.add_column(col, justify="left" if i < 2 else "right")
    for row in shares.rows:
        table.add_row(*row)
    return table


@warehouse_app.command("stats")
def stats_command(
    root: RootOpt = None,
    horizon_s: Annotated[float, typer.Option(min=0.0, help="Label horizon H, s.")] = 3.0,
    seed: Annotated[int, typer.Option(help="Split seed.")] = SplitSpec().seed,
    train_frac: Annotated[float, typer.Option(help="Train share of round-0 runs.")] =
        SplitSpec().train_frac,
    val_frac: Annotated[float, typer.Option(help="Validation share of round-0 runs.")] =
        SplitSpec().val_frac,
) -> None:
    """Per logical scenario and split: scenarios, violations, frames, unsafe frames."""
    try:
        splits = SplitSpec(seed, train_frac, val_frac)
    except ValueError as exc:
        _err().print(f"[red]error:[/] {exc}")
        raise typer.Exit(2) from exc
    rows = Warehouse(root).query(
        "dataset_stats", horizon_s=horizon_s, seed=splits.seed,
        train_frac=splits.train_frac, val_frac=splits.val_frac,
    ).to_pylist()
    table = Table(title=f"dataset statistics (H = {horizon_s:g} s, split seed {splits.seed})")
    for col in ("LS", "Set", "#Scena.", "#Viol. (%)", "#Frame", "#Unsafe (%)", "#Failed"):
        table.add_column(col, justify="left" if col in ("LS", "Set") else "right")
    for r in rows:
        table.add_row(
            r["logical_scenario"], r["split"], f"{r['scenarios']:,}",
            _count_pct(r["violations"], r["violations_pct"]), f"{r['frames']:,}",
            _count_pct(r["unsafe_frames"], r["unsafe_pct"]), str(r["failed"]),
        )
    _out().print(table)
    shares = Warehouse(root).query("attribution_shares", logical_scenario=None).to_pylist()
    if shares:
        _out().print(attribution_table(shares))
    if not rows:
        _out().print(f"the warehouse under {DataRoot.resolve(root).path} is empty: "
                      "run `evoeye ingest` first")
