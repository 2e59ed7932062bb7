"""`evoeye evaluate`: the paper's RQ1 table for the baselines and trained monitors."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.defaults import SPLIT_SEED, TRAIN_FRAC, VAL_FRAC
from evoeye.cli.errors import UserError
from evoeye.cli.output import StepBar
from evoeye.evaluation.baselines import BASELINE_SPECS
from evoeye.paths import DataRoot


def parse_baselines(text: str) -> list[str]:
    """'ttc,rss,aem' → names; '' or 'none' → none."""
    names = [n.strip() for n in text.split(",") if n.strip() and n.strip() != "none"]
    unknown = [n for n in names if n not in BASELINE_SPECS]
    if unknown:
        raise typer.BadParameter(f"unknown baseline(s) {', '.join(unknown)}; known: "
                                 f"{', '.join(BASELINE_SPECS)}")
    return names


@app.command("evaluate")
def evaluate_command(
    root: Annotated[Path | None, typer.Option(
        "--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data).")] = None,
    scenario: Annotated[list[str] | None, typer.Option(
        "--scenario", callback=scenario_check(recorded=True), help=scenario_help(
            "Logical scenario (repeat for several; default: all in the warehouse).",
            recorded=True))] = None,
    monitor: Annotated[list[str] | None, typer.Option(
        "--monitor", help="Trained monitor version to evaluate (repeatable).")] = None,
    baselines: Annotated[str, typer.Option(
        help=f"Comma-separated baselines: {', '.join(BASELINE_SPECS)} ('none' for none).")
    ] = ",".join(BASELINE_SPECS),
    fusion: Annotated[bool, typer.Option(
        "--train-fusion/--no-train-fusion",
        help="Also train a FusionMonitor per scenario (seed 0, L = 5) and evaluate it.")] = False,
    split_seed: Annotated[int, typer.Option(help="Split seed.")] = SPLIT_SEED,
    train_frac: Annotated[float, typer.Option(help="Train share of round-0 runs.")] = TRAIN_FRAC,
    val_frac: Annotated[float, typer.Option(help="Validation share of round-0 runs.")] =
        VAL_FRAC,
    test_batch: Annotated[str | None, typer.Option(
        help="A round-0 batch held out as the Test Set (its runs are always test).")] = None,
    latency: Annotated[bool, typer.Option(
        "--latency/--no-latency", help="Time inference on CPU (batch 1 and 1024).")] = True,
    store: Annotated[bool, typer.Option(
        "--store/--no-store", help="Write the scores to the warehouse (monitor_scores).")] = True,
    name: Annotated[str | None, typer.Option(
        help="Report folder name under <root>/reports (default rq1-<UTC time>).")] = None,
    as_json: Annotated[bool, typer.Option(
        "--json", help="Print the figures as JSON instead of the Markdown table.")] = False,
) -> None:
    """Score val and test splits, calibrate on val, and report the RQ1 figures on test."""
    from evoeye.evaluation.report import markdown_report
    from evoeye.evaluation.rq1 import rq1, rq1_report
    from evoeye.store import SplitSpec

    names = parse_baselines(baselines)
    if not names and not monitor and not fusion:
        raise typer.BadParameter("nothing to evaluate: give --monitor, --train-fusion or "
                                 "--baselines")
    try:
        splits = SplitSpec(split_seed, train_frac, val_frac, test_batch)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from exc
    data = DataRoot.existing(root)
    per_scenario = int(fusion) + int(bool(names)) + 1  # the steps rq1 reports per scenario
    total = per_scenario * len(scenario) if scenario else None
    try:
        with StepBar("evaluate", total=total) as bar:
            reports = rq1(data, scenario, baselines=names, monitor_versions=monitor or (),
                          fusion=fusion, splits=splits, latency=latency, store_scores=store,
                          progress=bar)
    except (ValueError, KeyError, RuntimeError) as exc:
        raise UserError(str(exc).strip("'\""), "check --scenario and --monitor, and that "
                        "`evoeye ingest` has run") from exc
    files = rq1_report(data, reports, name)
    dicts = [r.to_dict() for r in reports]
    if as_json:
        sys.stdout.write(json.dumps({"reports": dicts, "report_dir": str(files.folder)}) + "\n")
        return
    typer.echo(markdown_report(dicts))
    typer.echo(f"report: {files.html}")
