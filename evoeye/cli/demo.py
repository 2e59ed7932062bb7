"""`evoeye demo`: the main job on embedded defaults, end to end, and where its results are."""

from __future__ import annotations

from typing import Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.defaults import SCENARIO_NAMES
from evoeye.cli.errors import ExitCode
from evoeye.cli.output import out
from evoeye.cli.simulate import RootOpt, failures_code, simulate_batch, summary_table
from evoeye.cli.warehouse import ingest_into, print_stats
from evoeye.paths import DataRoot


@app.command()
def demo(
    root: RootOpt = None,
    n: Annotated[int, typer.Option("--n", min=1, help="Runs per logical scenario.")] = 20,
    seed: Annotated[int, typer.Option(min=0)] = 0,
    workers: Annotated[int, typer.Option(min=1)] = 2,
) -> None:
    """Simulate both logical scenarios, ingest the logs, print the dataset and where it all is.

    Exits 3 if any run failed or any log was quarantined.
    """
    data = DataRoot.resolve(root)
    rows = [(name, simulate_batch(name, n, seed, data, workers, batch="demo"))
            for name in SCENARIO_NAMES]
    out().print(summary_table("evoeye demo: simulate", rows))
    code = failures_code(rows)
    try:
        ingest_into(data)
    except typer.Exit as partial:
        code = ExitCode(partial.exit_code)
    print_stats(data)
    out().print(f"\nMCAP logs (open in Foxglove or Lichtblick): {data.runs}")
    out().print(f"warehouse (Parquet + DuckDB): {data.warehouse}")
    out().print(f'try: evoeye sql --root {data.path} "SELECT * FROM dataset_stats"')
    exit_with(code)
