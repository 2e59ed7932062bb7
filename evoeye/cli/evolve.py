"""`evoeye evolve` (one campaign, round by round) and `evoeye experiment` (the RQ2 table)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.defaults import UPDATE_MODES
from evoeye.cli.output import StepBar
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    from evoeye.evolve.campaign.config import CampaignConfig

FEEDBACK_HELP = ("ŷ in f_r = mean |ŷ − y|: raw monitor scores, or prior-corrected "
                 "(undo the training pos_weight).")
Root = Annotated[Path | None, typer.Option(
    "--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data).")]


def _config(scenario: str, strategy: str, budget_s: float, seed: int, monitor: str | None,
            n_round: int, update: str, epochs: int | None, split_seed: int,
            feedback: str = "raw", family: str = "fusion") -> CampaignConfig:
    from evoeye.evolve.campaign.config import CampaignConfig
    from evoeye.store import SplitSpec

    if update not in UPDATE_MODES:
        raise typer.BadParameter(f"--update must be one of {UPDATE_MODES}")
    try:
        return CampaignConfig(scenario=scenario, strategy=strategy, budget_s=budget_s, seed=seed,
                              monitor=monitor, n_round=n_round, update=update, epochs=epochs,
                              splits=SplitSpec(seed=split_seed), feedback=feedback,
                              family=family)
    except (ValueError, KeyError) as e:
        raise typer.BadParameter(str(e)) from None


@app.command("evolve")
def evolve_command(
    root: Root = None,
    scenario: Annotated[str, typer.Option("--scenario")] = "highway-cut-in",
    strategy: Annotated[str, typer.Option("--strategy")] = "evoeye",
    budget_s: Annotated[float, typer.Option("--budget-s", help="Simulated seconds.")] = 600.0,
    seed: Annotated[int, typer.Option("--seed")] = 0,
    monitor: Annotated[str | None, typer.Option("--monitor", help="G_0 version.")] = None,
    n_round: Annotated[int, typer.Option("--n-round")] = 20,
    update: Annotated[str, typer.Option("--update", help="finetune | retrain")] = "finetune",
    epochs: Annotated[int | None, typer.Option("--epochs")] = None,
    max_rounds: Annotated[int | None, typer.Option("--max-rounds")] = None,
    split_seed: Annotated[int, typer.Option("--split-seed")] = 0,
    feedback: Annotated[str, typer.Option("--feedback", help=FEEDBACK_HELP)] = "raw",
    family: Annotated[str, typer.Option("--family", help="The monitor evolved: fusion, or aem "
                                        "(AEM-Evo; judged on the FusionMonitor's Hard Set).")
                      ] = "fusion",
) -> None:
    """Run (or resume) an evolution campaign; per round, G_r's F1 / AUPRC on the test set."""
    from tqdm import tqdm

    from evoeye.evolve.campaign.assess import Assessor
    from evoeye.evolve.campaign.loop import Campaign

    cfg = _config(scenario, strategy, budget_s, seed, monitor, n_round, update, epochs,
                  split_seed, feedback, family)
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
        m = json.loads(row.metrics) if row.metrics else {}
        t, h = m.get("test", {}), m.get("hard", {})
        bar.write(f"round {row.round}: {len(row.scenario_ids)} runs, {row.simulated_s:.0f}/"
                  f"{cfg.budget_s:.0f} s, monitor {row.monitor_version} | test F1@0.05 "
                  f"{t.get('f1@0.05', 0):.3f} AUPRC {t.get('auprc') or 0:.3f} | hard F1@0.05 "
                  f"{h.get('f1@0.05', 0):.3f}")
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


@app.command("experiment")
def experiment_command(
    root: Root = None,
    scenario: Annotated[list[str] | None, typer.Option("--scenario")] = None,
    budget_s: Annotated[float | None, typer.Option(
        "--budget-s", help="Simulated seconds per campaign (default: the simulated time of the "
        "scenario's initial training data, as in the paper).")] = None,
    repetitions: Annotated[int, typer.Option("--repetitions", "-r")] = 3,
    n_round: Annotated[int, typer.Option("--n-round")] = 20,
    epochs: Annotated[int | None, typer.Option("--epochs")] = None,
    update: Annotated[str, typer.Option(
        "--update", help="Monitor update per round: finetune (from G_r) or retrain.")] = "finetune",
    monitor: Annotated[str | None, typer.Option(
        "--monitor", help="G_0 of the first --scenario (default: its newest monitor trained "
        "from scratch).")] = None,
    feedback: Annotated[str, typer.Option("--feedback", help=FEEDBACK_HELP)] = "raw",
    controls: Annotated[int, typer.Option(
        "--controls", min=0, help="G_0 retrained on the initial data with this many other "
        "seeds: the Hard-Set score a new model gets without new data.")] = 3,
    ablation: Annotated[bool, typer.Option("--ablation/--no-ablation")] = True,
    strategy: Annotated[list[str] | None, typer.Option(
        "--strategy", help="Run only these methods (repeatable): a strategy, or aem-evo "
        "(evoeye evolving the AEM baseline); default: the RQ2 ones, plus the ablations "
        "(no-feedback, no-density, aem-evo) unless --no-ablation.")] = None,
    name: Annotated[str | None, typer.Option("--name", help="Report folder name.")] = None,
) -> None:
    """The RQ2 table (+ evolution ablation): G_0 vs uniform / avfuzzer / evoeye, R seeds."""
    from evoeye.evolve.campaign.experiment import ABLATION, MAIN, methods, run_experiment
    from evoeye.evolve.campaign.report import write_experiment_report

    data = DataRoot.existing(root)
    scenarios = scenario or ["highway-cut-in", "unprotected-intersection"]
    unknown = sorted(set(strategy or ()) - set(methods()))
    if unknown:
        raise typer.BadParameter(f"unknown method {unknown}; known: {sorted(methods())}")
    if budget_s is not None and budget_s < 0:
        raise typer.BadParameter(f"--budget-s must be >= 0, got {budget_s}")
    base = _config(scenarios[0], "evoeye", budget_s or 0.0, 0, monitor, n_round, update, epochs,
                   0, feedback)
    with StepBar("experiment") as bar:  # a step: a campaign started or a round done
        results = run_experiment(data, scenarios, base,
                                 strategies=strategy or MAIN + (ABLATION if ablation else ()),
                                 seeds=range(repetitions), budget_s=budget_s, controls=controls,
                                 progress=bar)
    folder = write_experiment_report(data, results, name)
    typer.echo((folder / "rq2.md").read_text(encoding="utf-8"))
    typer.echo(f"report: {folder / 'rq2.html'}")
