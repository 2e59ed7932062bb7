"""`evoeye evolve` (one campaign, round by round) and `evoeye experiment` (the RQ2 table).

Their campaign options are `CampaignConfig`'s (`campaign_options`): `with_campaign_options`
adds one typer option per field to a command, so an option is declared once, in
`evoeye.evolve.campaign.config` (which imports nothing heavy, as `--help` requires).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Collection
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help, scenario_names
from evoeye.cli.defaults import FAMILY_NAMES, METHOD_NAMES, RECIPE_NAMES, STRATEGY_NAMES
from evoeye.cli.output import StepBar
from evoeye.evolve.campaign.config import FEEDBACK_MODES, UPDATE_MODES, campaign_options
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    from evoeye.evolve.campaign.config import CampaignConfig

Root = Annotated[Path | None, typer.Option(
    "--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data).")]


def choices(kind: str | None) -> tuple[str, ...]:
    """The values a campaign option naming a `kind` of thing takes (a KNOWN key of
    `evoeye.evolve.campaign.config`), as `--help` lists them; () for a free one."""
    listed = {"strategy": STRATEGY_NAMES, "update": UPDATE_MODES, "feedback": FEEDBACK_MODES,
              "family": FAMILY_NAMES, "recipe": RECIPE_NAMES}
    if kind == "scenario":
        return scenario_names()
    return tuple(listed.get(kind or "", ()))


def _help(text: str, kind: str | None) -> str:
    names = choices(kind)
    return f"{text} One of: {', '.join(names)}." if names else text


def with_campaign_options(exclude: Collection[str] = ()) -> Callable[[Callable], Callable]:
    """A command taking `options` (the campaign options given, by name) and its own parameters
    becomes one whose signature has a typer option per campaign option (minus `exclude`)."""
    def wrap(command: Callable) -> Callable:
        own = [p for p in inspect.signature(command, eval_str=True).parameters.values()
               if p.name != "options"]
        mine = campaign_options(exclude)
        added = [inspect.Parameter(o.name, inspect.Parameter.KEYWORD_ONLY, default=o.default,
                                   annotation=Annotated[o.type | None if o.optional else o.type,
                                                        typer.Option(
                                                            "--" + o.name.replace("_", "-"),
                                                            help=_help(o.help, o.names),
                                                            min=o.ge, max=o.le)])
                 for o in mine]

        @wraps(command)
        def with_options(**kwargs: Any) -> Any:
            options = {o.name: kwargs.pop(o.name) for o in mine}
            return command(options, **kwargs)

        params = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in own] + added
        with_options.__signature__ = inspect.Signature(params)  # type: ignore[attr-defined]
        with_options.__annotations__ = {p.name: p.annotation for p in params}
        del with_options.__wrapped__  # typer must see the new signature, not the command's
        return with_options
    return wrap


def _config(options: dict[str, Any], **fixed: Any) -> CampaignConfig:
    """The CampaignConfig of the options given (typer.BadParameter naming what is wrong)."""
    from evoeye.evolve.campaign.config import config_from

    try:
        return config_from(options, **fixed)
    except (ValueError, KeyError) as e:
        raise typer.BadParameter(str(e)) from None


@app.command("evolve")
@with_campaign_options()
def evolve_command(
    options: dict[str, Any],
    root: Root = None,
    max_rounds: Annotated[int | None, typer.Option(
        "--max-rounds", min=1, help="Rounds in this run (default: until the budget is spent).")
    ] = None,
) -> None:
    """Run (or resume) an evolution campaign; per round, G_r's F1 / AUPRC on the test set."""
    from tqdm import tqdm

    from evoeye.evolve.campaign.assess import Assessor
    from evoeye.evolve.campaign.experiment import brief
    from evoeye.evolve.campaign.loop import Campaign
    from evoeye.evolve.campaign.state import redrawn_note

    cfg = _config(options)
    if cfg.budget_s <= 0:
        raise typer.BadParameter(f"{cfg.budget_s:g} s leaves no run to simulate: give the "
                                 "simulated seconds the campaign may use", param_hint="--budget-s")
    data = DataRoot.existing(root)
    probe = Campaign(data, cfg)
    assess = Assessor.of(probe)
    campaign = Campaign(data, cfg, assess=assess)
    typer.echo(f"campaign {campaign.campaign_id}: logs in "
               f"{data.runs / cfg.scenario / campaign.campaign_id}, state in "
               f"{data.table_dir('campaign_rounds')} and {data.table_dir('feedback')}")

    # the bar counts simulated seconds of the budget; each round's line is printed above it
    bar = tqdm(total=round(cfg.budget_s), desc="evolve", unit="sim s")

    def show(row, state) -> None:
        bar.write(f"round {row.round}: {len(row.scenario_ids)} runs, {row.simulated_s:.0f}/"
                  f"{cfg.budget_s:.0f} s, monitor {row.monitor_version} | {brief(row.metrics)}"
                  + (f" | {note}" if (note := redrawn_note(state)) else ""))
        bar.update(max(0, min(round(state.spent_s), bar.total) - bar.n))
        bar.set_postfix_str(f"round {row.round}")

    try:
        state = campaign.start()
        show(state.rounds[-1], state)
        state = campaign.run(max_rounds=max_rounds, on_round=show)
    finally:
        bar.close()
    typer.echo(f"{'budget spent' if campaign.done(state) else 'paused'} after round "
               f"{state.round}: {state.acquired} runs, {state.spent_s:.0f} s; monitor "
               f"{state.monitor}")


# options the experiment sets per campaign (its own --scenario, --strategy, --budget-s, seeds)
PER_CAMPAIGN = ("scenario", "strategy", "seed", "budget_s", "family", "reference")


@app.command("experiment")
@with_campaign_options(exclude=PER_CAMPAIGN)
def experiment_command(
    options: dict[str, Any],
    root: Root = None,
    scenario: Annotated[list[str] | None, typer.Option(
        "--scenario", callback=scenario_check(), help=scenario_help(
            "Logical scenarios (repeatable; default: every one). The first one's G_0 is "
            "--monitor."))] = None,
    budget_s: Annotated[float | None, typer.Option(
        "--budget-s", min=0.0, help="Simulated seconds per campaign (default: the simulated "
        "time of the scenario's initial training data, as in the paper).")] = None,
    repetitions: Annotated[int, typer.Option("--repetitions", "-r", min=1)] = 3,
    controls: Annotated[int, typer.Option(
        "--controls", min=0, help="G_0 retrained on the initial data with this many other "
        "seeds: the Hard-Set score a new model gets without new data.")] = 3,
    ablation: Annotated[bool, typer.Option("--ablation/--no-ablation")] = True,
    strategy: Annotated[list[str] | None, typer.Option(
        "--strategy", help="Run only these methods (repeatable): a strategy, or <family>-evo "
        "(evoeye evolving another monitor family); default: the RQ2 ones, plus the ablations "
        "(no-feedback, no-density, aem-evo) unless --no-ablation. One of: "
        f"{', '.join(METHOD_NAMES)}.")] = None,
    name: Annotated[str | None, typer.Option("--name", help="Report folder name.")] = None,
    workers: Annotated[int | None, typer.Option(
        "--workers", min=1, help="Campaigns run side by side in this many local processes "
        "(default: one per CPU; 1: one after another).")] = None,
    dask_address: Annotated[str | None, typer.Option(
        "--dask-address", help="Run the campaigns on the Dask cluster at this scheduler "
        "address instead, one per worker (give the workers one thread each).")] = None,
) -> None:
    """The RQ2 table (+ evolution ablation): G_0 vs uniform / avfuzzer / evoeye, R seeds."""
    from evoeye.evolve.campaign.config import check_known
    from evoeye.evolve.campaign.experiment import ABLATION, MAIN, run_experiment
    from evoeye.evolve.campaign.report import write_experiment_report

    data = DataRoot.existing(root)
    scenarios = scenario or list(scenario_names())
    try:
        check_known("method", strategy or MAIN)
    except ValueError as e:
        raise typer.BadParameter(str(e)) from None
    base = _config(options, scenario=scenarios[0], budget_s=budget_s or 0.0)
    with StepBar("experiment") as bar:  # a step: a campaign started or a round done
        results = run_experiment(data, scenarios, base,
                                 strategies=strategy or MAIN + (ABLATION if ablation else ()),
                                 seeds=range(repetitions), budget_s=budget_s, controls=controls,
                                 progress=bar, workers=workers, dask_address=dask_address)
    folder = write_experiment_report(data, results, name)
    typer.echo((folder / "rq2.md").read_text(encoding="utf-8"))
    typer.echo(f"report: {folder / 'rq2.html'}")
