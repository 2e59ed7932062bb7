"""`evoeye simulate`: a batch of uniformly sampled runs of one logical scenario, as MCAP logs."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table
from tqdm import tqdm

from evoeye.batch import BatchSummary, plan_uniform, run_batch
from evoeye.cli.app import app
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS, ScenarioError

console = Console()

RootOpt = Annotated[
    Path | None,
    typer.Option("--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data)."),
]


def summary_table(title: str, rows: list[tuple[str, BatchSummary]]) -> Table:
    """One row per batch: runs, collisions, failures, skipped, simulated and wall time."""
    table = Table(title=title)
    for col in ("scenario", "runs", "collisions", "failures", "skipped", "sim s", "wall s", "× rt"):
        table.add_column(col, justify="left" if col == "scenario" else "right")
    for name, s in rows:
        done = s.runs - s.skipped
        share = f"{s.collisions} ({100.0 * s.collisions / max(1, s.runs):.0f} %)"
        rtf = f"{s.simulated_s / s.wall_s:.0f}" if done and s.wall_s > 0 else "-"
        table.add_row(name, str(s.runs), share, str(s.failures), str(s.skipped),
                      f"{s.simulated_s:.0f}", f"{s.wall_s:.1f}", rtf)
    return table


def simulate_batch(scenario: str, n: int, seed: int, root: Path, workers: int,
                   batch: str | None = None) -> BatchSummary:
    """Plan, run with a progress bar, and report failures by scenario id."""
    specs = plan_uniform(scenario, n, seed, batch=batch)
    bar = lambda it: tqdm(it, total=len(specs), desc=scenario, unit="run")  # noqa: E731
    summary = run_batch(specs, root, workers=workers, progress=bar)
    for r in summary.results:
        if r.status != "ok":
            console.print(f"[yellow]{r.status}[/] {r.scenario_id}: {r.reason}")
    return summary


@app.command()
def simulate(
    scenario: Annotated[str, typer.Option(help=f"Logical scenario: {', '.join(SCENARIOS)}.")],
    n: Annotated[int, typer.Option("--n", min=1, help="Number of runs.")] = 10,
    seed: Annotated[int, typer.Option(min=0, help="Batch seed: fixes vectors and run seeds.")] = 0,
    root: RootOpt = None,
    workers: Annotated[int, typer.Option(min=1, help="Worker processes.")] = 1,
    batch: Annotated[str | None, typer.Option(help="Batch name (default uniform-seed<S>).")] = None,
) -> None:
    """Simulate N uniformly sampled concrete scenarios and write one MCAP log per run."""
    data = DataRoot.at(root)
    try:
        summary = simulate_batch(scenario, n, seed, data.path, workers, batch)
    except (ScenarioError, ValueError) as exc:
        console.print(f"[red]error:[/] {exc}")
        raise typer.Exit(2) from exc
    console.print(summary_table("simulate", [(scenario, summary)]))
    console.print(f"logs: {data.runs / scenario}")
