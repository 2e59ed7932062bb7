"""`evoeye predictability`: is search worth it here? θ-predictability of outcome and error.

A command of its own rather than a part of `evoeye audit`: the audit judges whether a batch's
runs are realistic from their logs; this asks whether acquisition can gain anything on a
regime, and needs a monitor's scores and fresh simulations, which an audit should not run.
"""

from __future__ import annotations

import shlex
import sys
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.defaults import ADS_PROFILE_NAMES
from evoeye.cli.output import out
from evoeye.cli.simulate import RootOpt, known_profile, plain_batch
from evoeye.paths import DataRoot


def _profile(name: str | None) -> str | None:
    return None if name is None else known_profile(name)


@app.command("predictability")
def predictability_command(
    root: RootOpt = None,
    scenario: Annotated[list[str] | None, typer.Option(
        "--scenario", callback=scenario_check(recorded=True),
        help=scenario_help("Logical scenario (repeatable; default: every one with runs).",
                           recorded=True))
    ] = None,
    batch: Annotated[str | None, typer.Option(
        callback=plain_batch, help="Only the runs of this batch (default: all).")] = None,
    ads: Annotated[str | None, typer.Option(
        "--ads", callback=_profile, help=f"Only runs of this ADS profile: "
        f"{', '.join(ADS_PROFILE_NAMES)} (default: the runs' one; several is an error).")
    ] = None,
    monitor: Annotated[str | None, typer.Option(
        help="Whose error to predict (default: the scenario's initial FusionMonitor); only "
        "runs it did not train on count.")] = None,
    feedback: Annotated[str, typer.Option(
        help="ŷ in the error mean |ŷ − y|: raw or prior-corrected.")] = "raw",
    sample: Annotated[int, typer.Option(
        min=0, help="θ re-simulated for the label noise (0: none).")] = 30,
    seeds: Annotated[int, typer.Option(
        min=0, help="New seeds per re-simulated θ (0: none).")] = 4,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the folds and the sample.")] = 0,
    workers: Annotated[int, typer.Option(min=1, help="Processes re-simulating.")] = 1,
    as_json: Annotated[bool, typer.Option("--json", help="Print the report as JSON.")] = False,
) -> None:
    """How well θ alone predicts a run's collision and a monitor's error, and how often a new
    seed flips the outcome; write reports/predictability-<S>-<B>/."""
    import orjson

    from evoeye.evolve.campaign.config import FEEDBACK_MODES
    from evoeye.evolve.predictability.check import check_regime
    from evoeye.evolve.predictability.report import markdown, write_report
    from evoeye.store import Warehouse

    if feedback not in FEEDBACK_MODES:
        raise typer.BadParameter(f"unknown feedback {feedback!r}; known: {FEEDBACK_MODES}")
    if monitor and len(scenario or []) != 1:
        raise typer.BadParameter("--monitor needs exactly one --scenario")
    data = DataRoot.existing(root)
    names = scenario or [r["logical_scenario"] for r in
                         Warehouse(data).query("logical_scenarios").to_pylist()]
    regimes = [check_regime(data, s, batch=batch, ads=ads, monitor=monitor, feedback=feedback,
                            sample=sample, seeds=seeds, seed=seed, workers=workers)
               for s in names]
    command = "evoeye " + shlex.join(sys.argv[1:])
    folder = write_report(data, regimes, scenario[0] if scenario and len(scenario) == 1
                          else None, batch, command)
    if as_json:
        sys.stdout.write(orjson.dumps({"command": command, "regimes": regimes},
                                      option=orjson.OPT_SERIALIZE_NUMPY).decode() + "\n")
    else:
        out().print(markdown(regimes, command), markup=False, highlight=False)
        out().print(f"report: {folder / 'predictability.md'}")
