"""`evoeye demo`: the main job on embedded defaults, end to end, and where its results are."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.simulate import RootOpt, console, simulate_batch, summary_table
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS


@app.command()
def demo(
    root: RootOpt = None,
    n: Annotated[int, typer.Option("--n", min=1, help="Runs per logical scenario.")] = 20,
    seed: Annotated[int, typer.Option(min=0)] = 0,
    workers: Annotated[int, typer.Option(min=1)] = 2,
) -> None:
    """Simulate a batch of both logical scenarios and print where the logs are."""
    data = DataRoot.at(root)
    rows = []
    for name in SCENARIOS:
        rows.append((name, simulate_batch(name, n, seed, data.path, workers, batch="demo")))
    console.print(summary_table("evoeye demo", rows))
    console.print(f"MCAP logs (open in Foxglove or Lichtblick): {Path(data.runs).resolve()}")
