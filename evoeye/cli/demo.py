"""`evoeye demo`: what the monitor achieves on fresh runs, in plain words, and where it all is."""

from __future__ import annotations

from typing import Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.defaults import SCENARIO_NAMES
from evoeye.cli.errors import ExitCode
from evoeye.cli.output import StepBar, out
from evoeye.cli.simulate import RootOpt, failures_code, simulate_batch, summary_table
from evoeye.cli.warehouse import ingest_into
from evoeye.paths import DataRoot


@app.command()
def demo(
    root: RootOpt = None,
    n: Annotated[int | None, typer.Option(
        "--n", min=8, help="Runs per logical scenario (default: 120 highway-cut-in, 60 "
        "unprotected-intersection: enough test collisions to compare monitors).")] = None,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the demo's runs.")] = 0,
    workers: Annotated[int, typer.Option(min=1)] = 2,
    evolve_runs: Annotated[int, typer.Option(
        "--evolve-runs", min=1, help="Runs of the evolution round, per scenario.")] = 4,
) -> None:
    """Simulate fresh runs, measure the shipped FusionMonitor against the rule-based baselines,
    run one evolution round, and say in plain words what they achieve.

    Per scenario: collisions warned of, how early, and false alarms per hour of safe driving,
    each with its 95 % interval; then what the evolution round changed. Exits 3 if any run
    failed or any log was quarantined.
    """
    from evoeye.results import demo as steps

    data = DataRoot.resolve(root)
    rows = [(name, simulate_batch(name, n or steps.RUNS[name], seed, data, workers,
                                  batch=steps.BATCH)) for name in SCENARIO_NAMES]
    out().print(summary_table("evoeye demo: simulate", rows))
    code = failures_code(rows)
    try:
        ingest_into(data)
    except typer.Exit as partial:
        code = ExitCode(partial.exit_code)
    with StepBar("demo", total=2 * len(SCENARIO_NAMES)) as bar:
        reports, rounds = [], {}
        for name in SCENARIO_NAMES:
            bar(f"{name}: the shipped FusionMonitor against the rule-based baselines")
            reports.append(steps.evaluate_shipped(data, name))
        for name in SCENARIO_NAMES:
            bar(f"{name}: one evolution round of {evolve_runs} runs")
            rounds[name] = steps.run_round(data, name, evolve_runs)
    result = steps.DemoResult(data, reports, rounds)
    steps.write_summary(result)
    console = out()
    console.print("\n" + steps.summary_text(result), markup=False, highlight=False)
    console.print("\nWhere the results are:")
    for what, path in result.paths():
        console.print(f"  {what}: {path}", markup=False, highlight=False)
    exit_with(code)
