"""`evoeye ingest`, `evoeye sql` and `evoeye warehouse stats`: the warehouse from the shell."""

from __future__ import annotations

import csv
import sys
from dataclasses import asdict
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.defaults import HORIZON_S, RUNS_PER_PART, SPLIT_SEED, TRAIN_FRAC, VAL_FRAC
from evoeye.cli.errors import ExitCode, UserError
from evoeye.cli.output import err, out, table
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    import pyarrow as pa
    from rich.table import Table

    from evoeye.store import SplitSpec
    from evoeye.store.ingest import IngestReport

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
    t = table("ingest", ["what", "count"], left=("what",), show_header=False)
    t.add_row("runs ingested", str(len(report.ingested)))
    t.add_row("frames ingested", f"{report.frames:,}")
    t.add_row("already in the warehouse", str(report.skipped))
    t.add_row("duplicate scenario ids", str(len(report.duplicates)))
    t.add_row("quarantined", str(len(report.quarantined)))
    if report.left_out:
        t.add_row("left out (a world variant's runs)", str(len(report.left_out)))
    t.add_row("parts of a killed ingest removed", str(len(report.orphans_removed)))
    return t


@app.command("ingest")
def ingest_command(
    root: RootOpt = None,
    runs_per_part: Annotated[
        int, typer.Option(min=1, help="Runs per Parquet part file.")
    ] = RUNS_PER_PART,
    workers: Annotated[int, typer.Option(
        min=1, help="Processes reading logs side by side (the warehouse is the same).")] = 1,
) -> None:
    """Append every run log under <root>/runs not yet ingested to the warehouse.

    Exits 3 if any log was quarantined (listed with its reason).
    """
    ingest_into(DataRoot.resolve(root), runs_per_part, workers)


def ingest_into(data: DataRoot, runs_per_part: int = RUNS_PER_PART, workers: int = 1) -> None:
    """Ingest with a progress bar, print the report; exit 3 if any log was quarantined."""
    from tqdm import tqdm

    from evoeye.store import ingest
    from evoeye.store.ingest import discover_logs
    from evoeye.store.schema import LAYOUT_VERSION

    if not discover_logs(data.runs):
        err().print(f"[yellow]warning:[/] no run logs under {data.runs}: nothing to ingest "
                    "(`evoeye simulate --scenario NAME` writes some there)")
        if not data.warehouse.is_dir():
            return  # nothing to create a warehouse for
    elif not data.warehouse.is_dir():
        where = "" if data.path.is_dir() else " (the data root does not exist yet)"
        err().print(f"creating a new warehouse at {data.warehouse}{where}")
    bars: list[tqdm] = []  # made once ingest knows how many logs it will read
    try:
        report = ingest(data, runs_per_part=runs_per_part, workers=workers,
                        on_start=lambda n: bars.append(tqdm(total=n, desc="ingest", unit="log")),
                        on_log=lambda p: bars[0].update(1))
    finally:
        for bar in bars:
            bar.close()
    console = out()
    if report.migrated:
        console.print(f"migrated {len(report.migrated)} warehouse parts to layout "
                      f"{LAYOUT_VERSION} in place")
    console.print(report_table(report))
    for log, reason in report.quarantined:
        console.print(f"[yellow]quarantined[/] {log}: {reason}")
    for log in report.duplicates:
        console.print(f"[yellow]duplicate[/] {log}: its scenario id is already ingested")
    if report.catalog_error:
        console.print(f"[yellow]warning:[/] views not refreshed ({report.catalog_error}); "
                      "the data is in, the next ingest refreshes them")
    console.print(f"warehouse: {data.warehouse}  (DuckDB: {data.duckdb_file})")
    if report.quarantined:
        err().print(f"[red]{len(report.quarantined)} logs quarantined[/] under {data.quarantine}"
                    " (reasons above); exit code 3")
        exit_with(ExitCode.PARTIAL)


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
    t = table(None, result.column_names, left=tuple(result.column_names))
    for row in result.slice(0, max_rows).to_pylist():
        t.add_row(*(_cell(v) for v in row.values()))
    out().print(t)
    if result.num_rows > max_rows:
        out().print(f"… {result.num_rows - max_rows} more rows (--max-rows, or --format csv)")


def _csv_cell(value: Any) -> Any:
    import orjson

    return orjson.dumps(value, default=str).decode() if isinstance(value, list | dict) else value


def write_csv(result: pa.Table) -> None:
    writer = csv.writer(sys.stdout, lineterminator="\n")
    writer.writerow(result.column_names)
    for row in result.to_pylist():
        writer.writerow([_csv_cell(v) for v in row.values()])


def write_json(result: pa.Table) -> None:
    import orjson

    sys.stdout.write(orjson.dumps(result.to_pylist(), default=str,
                                  option=orjson.OPT_SERIALIZE_NUMPY).decode() + "\n")


def _holds_runs(data: DataRoot) -> bool:
    """Whether the warehouse holds any ingested run."""
    from evoeye.store import Warehouse

    query = "SELECT count(*) AS n FROM scenarios"
    return bool(Warehouse(data).read_only_sql(query).column("n")[0].as_py())


@app.command("sql")
def sql_command(
    query: Annotated[str, typer.Argument(help="SQL over the warehouse views, e.g. "
                                             "\"SELECT * FROM dataset_stats\".")],
    root: RootOpt = None,
    fmt: Annotated[Format, typer.Option("--format", help="Output format.")] = Format.table,
    max_rows: Annotated[int, typer.Option(min=1, help="Rows shown in table format.")] = 50,
    allow_files: Annotated[bool, typer.Option(
        "--allow-files", help="Also let the query read files outside the warehouse "
        "(read_csv, read_parquet, …); it still cannot write.")] = False,
) -> None:
    """Run a read-only query against the warehouse views (SELECT / EXPLAIN only; no ATTACH,
    COPY, INSTALL or SET, and no file outside the warehouse unless --allow-files)."""
    import duckdb

    from evoeye.store import Warehouse
    from evoeye.store.catalog import ReadOnlyQueryError

    data = DataRoot.existing(root)
    try:
        result = Warehouse(data).read_only_sql(query, allow_files=allow_files)
    except ReadOnlyQueryError as exc:
        raise UserError(str(exc), "`evoeye ingest` is the only writer") from exc
    except duckdb.PermissionException as exc:
        raise UserError(str(exc), "--allow-files lets a query read other files") from exc
    except duckdb.Error as exc:
        raise UserError(str(exc), "the views are listed in docs/warehouse.md") from exc
    if result.num_rows == 0 and not _holds_runs(data):
        err().print(f"[yellow]warning:[/] the warehouse at {data.warehouse} holds no run yet: "
                    "`evoeye simulate`, then `evoeye ingest`, fill it")
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
    from evoeye.evaluation import report

    shares = report.attribution_table(rows)
    t = table("root causes of collisions (evoeye explain), %", shares.header,
              left=(shares.header[0],))
    for row in shares.rows:
        t.add_row(*row)
    return t


@warehouse_app.command("stats")
def stats_command(
    root: RootOpt = None,
    horizon_s: Annotated[float, typer.Option(min=0.0, help="Label horizon H, s.")] = HORIZON_S,
    seed: Annotated[int, typer.Option(help="Split seed.")] = SPLIT_SEED,
    train_frac: Annotated[float, typer.Option(help="Train share of round-0 runs.")] = TRAIN_FRAC,
    val_frac: Annotated[float, typer.Option(help="Validation share of round-0 runs.")] =
        VAL_FRAC,
    test_batch: Annotated[str | None, typer.Option(
        help="A round-0 batch held out as the Test Set (its runs are always test).")] = None,
) -> None:
    """Per logical scenario and split: scenarios, violations, frames, unsafe frames."""
    from evoeye.store import SplitSpec

    data = DataRoot.existing(root)
    try:
        splits = SplitSpec(seed, train_frac, val_frac, test_batch)
    except ValueError as exc:
        raise UserError(str(exc), "see `evoeye warehouse stats --help`") from exc
    print_stats(data, horizon_s, splits)


def print_stats(data: DataRoot, horizon_s: float = HORIZON_S, splits: SplitSpec | None = None
                ) -> None:
    """The dataset statistics table (and the root causes, if explained) of a data root."""
    from evoeye.store import SplitSpec, Warehouse

    splits = splits or SplitSpec()
    rows = Warehouse(data).query(
        "dataset_stats", horizon_s=horizon_s, **asdict(splits)).to_pylist()
    t = table(f"dataset statistics (H = {horizon_s:g} s, split seed {splits.seed})",
              ["LS", "Set", "#Scena.", "#Viol. (%)", "#Frame", "#Unsafe (%)", "#Failed"],
              left=("LS", "Set"))
    for r in rows:
        t.add_row(
            r["logical_scenario"], r["split"], f"{r['scenarios']:,}",
            _count_pct(r["violations"], r["violations_pct"]), f"{r['frames']:,}",
            _count_pct(r["unsafe_frames"], r["unsafe_pct"]), str(r["failed"]),
        )
    out().print(t)
    shares = Warehouse(data).query("attribution_shares", logical_scenario=None).to_pylist()
    if shares:
        out().print(attribution_table(shares))
    if not rows:
        out().print(f"the warehouse under {data.path} is empty: run `evoeye ingest` first")
