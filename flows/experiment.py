"""Flow: the RQ2 experiment — every (scenario, seed, method) campaign as an evolution flow run.

Each campaign is a sub-flow run named `<scenario>-<method>-s<seed>` whose rounds are in turn
`round-<r>` flow runs, so the UI shows the experiment's progress round by round. Campaigns are
resumable, so a crashed experiment flow run is simply started again. The RQ2 and ablation tables
are written under `<root>/reports/<name>/` and published as a Markdown artifact.
"""

from __future__ import annotations

from typing import Any

from prefect import flow, get_run_logger
from prefect.artifacts import create_markdown_artifact
from pydantic import Field

from evoeye.evolve.campaign.config import CampaignConfig, config_from
from evoeye.evolve.campaign.experiment import (
    ABLATION,
    MAIN,
    add_controls,
    collect_results,
    method_of,
    plan_experiment,
)
from evoeye.evolve.campaign.report import markdown, write_experiment_report
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from flows.campaign_params import KnownNames, campaign_model
from flows.evolve import EvolveParams, evolution_flow

# options the experiment sets per campaign; the others apply to all of its campaigns
PER_CAMPAIGN = ("scenario", "strategy", "seed", "budget_s", "family", "reference")


class ExperimentRun(KnownNames):
    """The experiment (defaults: the paper's — both scenarios, 3 seeds, budget = initial data)."""

    names = {"scenarios": "scenario", "strategies": "method"}

    root: str | None = None
    scenarios: list[str] = Field(default_factory=lambda: list(SCENARIOS))
    strategies: list[str] = Field(default_factory=lambda: list(MAIN + ABLATION))  # methods
    repetitions: int = Field(3, ge=1)
    budget_s: float | None = Field(None, ge=0.0)  # None: simulated time of the initial data
    controls: int = Field(3, ge=0)  # re-seeded G_0 per scenario (no new data)
    report_name: str | None = None

    def base(self) -> CampaignConfig:
        """The options every campaign shares (the first scenario's, whose G_0 `monitor` is)."""
        return config_from(self.model_dump(exclude={"budget_s"}), scenario=self.scenarios[0],
                           budget_s=self.budget_s or 0.0)


ExperimentParams = campaign_model("ExperimentParams", ExperimentRun, __name__,
                                  exclude=PER_CAMPAIGN)


@flow(name="evoeye-experiment", log_prints=True)
def experiment_flow(params: ExperimentParams | None = None) -> dict[str, Any]:
    """Run (or resume) every campaign, then write and publish the RQ2 report."""
    params = params or ExperimentParams()
    root = DataRoot.resolve(params.root)
    plan = plan_experiment(root, params.scenarios, params.base(), strategies=params.strategies,
                           seeds=range(params.repetitions), budget_s=params.budget_s)
    for cfg in plan:
        name = f"{cfg.scenario}-{method_of(cfg)}-s{cfg.seed}"
        evolution_flow.with_options(flow_run_name=name)(
            EvolveParams.of(cfg, str(root.path), assess=True))
    results = add_controls(root, plan, collect_results(root, plan), params.controls)
    folder = write_experiment_report(root, results, params.report_name)
    create_markdown_artifact(markdown=markdown(results), key="evoeye-rq2",
                             description=f"RQ2 report, {folder / 'rq2.html'}")
    get_run_logger().info("RQ2 report: %s", folder / "rq2.html")
    return {"report_dir": str(folder), "campaigns": len(plan), "results": results}


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(ExperimentParams, experiment_flow, __doc__)
