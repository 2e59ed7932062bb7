"""`evoeye demo`: what the monitor achieves on fresh runs, in plain words, and where it all is."""

from __future__ import annotations

from typing import Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.choices import scenario_help, scenario_names
from evoeye.cli.errors import ExitCode, UserError
from evoeye.cli.output import StepBar, err, out
from evoeye.cli.simulate import RootOpt, failures_code, simulate_batch, summary_table
from evoeye.cli.warehouse import ingest_into
from evoeye.paths import DataRoot


def scenario_list(text: str | None) -> list[str] | None:
    """Typer callback: "a,b" → the registered scenarios a and b, or a one-line error naming
    the known ones."""
    if text is None:
        return None
    from evoeye.scenarios import ScenarioError, simulable

    names = [name.strip() for name in text.split(",") if name.strip()]
    try:
        return [simulable(name).name for name in names] or None
    except ScenarioError as exc:
        raise typer.BadParameter(str(exc)) from None


@app.command()
def demo(
    root: RootOpt = None,
    scenario: Annotated[str | None, typer.Option(
        "--scenario", callback=scenario_list, help=scenario_help(
            "Run only these logical scenarios (NAME[,NAME]; default: every one that ships a "
            "demo monitor; the others are skipped, with a line saying so)."))] = None,
    n: Annotated[int | None, typer.Option(
        "--n", min=8, help="Runs per logical scenario (default: the scenario's own, enough "
        "test collisions to compare monitors: 120 on the highway, 60 at the intersection)."
    )] = None,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the demo's runs.")] = 0,
    workers: Annotated[int, typer.Option(min=1)] = 2,
    evolve_runs: Annotated[int, typer.Option(
        "--evolve-runs", min=1, help="Runs of the evolution round, per scenario.")] = 4,
) -> None:
    """Simulate fresh runs, measure the shipped FusionMonitor against the rule-based baselines,
    use each as the trigger of an emergency brake, run one evolution round, and say in plain
    words what they achieve.

    Per scenario: collisions warned of, how early, and false alarms per hour of safe driving,
    each with its 95 % interval; in the loop, collisions prevented and caused and false
    interventions per hour, beside the oracle; then what the evolution round changed. Exits 3
    if any run failed or any log was quarantined.
    """
    from evoeye.results import demo as steps

    names, skipped = steps.plan(scenario or scenario_names())
    if skipped:
        err().print(steps.skipped_line(skipped), markup=False, highlight=False)
    if not names:
        raise UserError("no scenario to run: none of them ships a demo monitor",
                        "train one with `make demo-monitors`, or pick others with --scenario")
    data = DataRoot.resolve(root)
    rows = [(name, simulate_batch(name, n or steps.runs_of(name), seed, data, workers,
                                  batch=steps.BATCH)) for name in names]
    out().print(summary_table("evoeye demo: simulate", rows))
    code = failures_code(rows)
    try:
        ingest_into(data, workers=workers)
    except typer.Exit as partial:
        code = ExitCode(partial.exit_code)
    with StepBar("demo", total=3 * len(names)) as bar:
        reports, rounds, loop = [], {}, {}
        for name in names:
            bar(f"{name}: the shipped FusionMonitor against the rule-based baselines")
            reports.append(steps.evaluate_shipped(data, name))
        for name in names:
            bar(f"{name}: the FusionMonitor and TTC-2D as triggers of an emergency brake")
            loop[name] = steps.supervise_shipped(data, name, workers)
        for name in names:
            bar(f"{name}: one evolution round of {evolve_runs} runs")
            rounds[name] = steps.run_round(data, name, evolve_runs)
    result = steps.DemoResult(data, reports, rounds, loop=loop)
    steps.write_summary(result)
    console = out()
    console.print("\n" + steps.summary_text(result), markup=False, highlight=False)
    console.print("\nWhere the results are:")
    for what, path in result.paths():
        console.print(f"  {what}: {path}", markup=False, highlight=False)
    exit_with(code)
