"""Flow: the RQ2 experiment — every (scenario, seed, method) campaign a task, side by side.

The campaigns are independent: each is a task run named `<scenario>-<method>-s<seed>` that runs
the campaign to its budget (`evoeye.evolve.campaign.workers.run_campaign`), fanned out over the
task runner — `workers` local processes, or the Dask cluster at `dask_address` (prefect-dask),
one campaign per worker. What they would all write alike (G_0's round 0) is written first.
Campaigns are resumable, so a crashed experiment flow run is simply started again. The RQ2 and
ablation tables are written under `<root>/reports/<name>/` and published as a Markdown artifact.
"""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import Any

from prefect import flow, get_run_logger, task
from prefect.cache_policies import NONE
from prefect.futures import as_completed
from pydantic import Field

from evoeye.evolve.campaign.cluster import check_cluster, loopback_api_note
from evoeye.evolve.campaign.config import CampaignConfig, config_from
from evoeye.evolve.campaign.experiment import (
    ABLATION,
    MAIN,
    add_controls,
    brief,
    campaign_jobs,
    collect_results,
    method_of,
    plan_experiment,
)
from evoeye.evolve.campaign.guard import stop_file
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.report import markdown, write_experiment_report
from evoeye.evolve.campaign.workers import (
    CampaignDone,
    CampaignJob,
    prepare_campaigns,
    run_campaign,
)
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from evoeye.store.ingest import refresh_catalog
from flows.api import shared_with_workers
from flows.campaign_params import KnownNames, campaign_model
from flows.published import named, publish
from flows.runners import task_runner

# options the experiment sets per campaign; the others apply to all of its campaigns
PER_CAMPAIGN = ("scenario", "strategy", "seed", "budget_s", "family", "reference")


class ExperimentRun(KnownNames):
    """The experiment (defaults: every registered scenario, 3 seeds, budget = initial data)."""

    names = {"scenarios": "scenario", "strategies": "method"}

    root: str | None = None
    scenarios: list[str] = Field(default_factory=lambda: list(SCENARIOS))
    strategies: list[str] = Field(default_factory=lambda: list(MAIN + ABLATION))  # methods
    repetitions: int = Field(3, ge=1)
    budget_s: float | None = Field(None, ge=0.0)  # None: simulated time of the initial data
    controls: int = Field(3, ge=0)  # re-seeded G_0 per scenario (no new data)
    report_name: str | None = None
    workers: int = Field(2, ge=1, le=64)  # local processes running campaigns side by side
    dask_address: str | None = None  # or the Dask scheduler whose workers run them

    def run_name(self) -> str:
        return (f"experiment-{'-'.join(self.scenarios)}-{len(self.strategies)}-methods-"
                f"r{self.repetitions}")

    def base(self) -> CampaignConfig:
        """The options every campaign shares (the first scenario's, whose G_0 `monitor` is)."""
        return config_from(self.model_dump(exclude={"budget_s"}), scenario=self.scenarios[0],
                           budget_s=self.budget_s or 0.0)


ExperimentParams = campaign_model("ExperimentParams", ExperimentRun, __name__,
                                  exclude=PER_CAMPAIGN)


@task(cache_policy=NONE, task_run_name="{name}")
def campaign(job: CampaignJob, name: str, stop: str) -> CampaignDone:
    """One campaign, run (or resumed) to its budget in a worker, until the file `stop` exists."""
    return run_campaign(job, brief, say=print, should_stop=Path(stop).exists)


@flow(name="evoeye-experiment-campaigns", log_prints=True)
def campaigns_flow(jobs: list[CampaignJob], names: list[str]) -> list[CampaignDone]:
    """Every campaign as a task on the flow's task runner (experiment_flow picks it). If one
    fails, the others are asked to stop (a stop file on the root: `guard.py`) and waited for."""
    if not jobs:
        return []
    stop = stop_file(DataRoot.resolve(jobs[0].root), uuid.uuid4().hex[:12])
    futures = [campaign.submit(job, name, str(stop))
               for job, name in zip(jobs, names, strict=True)]
    try:
        for future in as_completed(futures):  # the first failure, as soon as it happens
            future.result()
        return [f.result() for f in futures]
    except BaseException:
        stop.parent.mkdir(parents=True, exist_ok=True)
        stop.touch()
        for f in futures:
            f.wait()
        raise
    finally:
        stop.unlink(missing_ok=True)


@flow(name="evoeye-experiment", log_prints=True,
      flow_run_name=named(lambda p: (p or ExperimentParams()).run_name()))
def experiment_flow(params: ExperimentParams | None = None) -> dict[str, Any]:
    """Run (or resume) every campaign, then write and publish the RQ2 report."""
    params = params or ExperimentParams()
    root = DataRoot.resolve(params.root)
    plan = plan_experiment(root, params.scenarios, params.base(), strategies=params.strategies,
                           seeds=range(params.repetitions), budget_s=params.budget_s)
    jobs = campaign_jobs(root, plan)
    if params.dask_address:  # every worker sees the root and runs this evoeye (cluster.py)
        check_cluster(params.dask_address, str(root.path),
                      sorted({Campaign(root, c).reference for c in plan}))
    prepare_campaigns(jobs)
    runner = task_runner(params.workers, params.dask_address)
    with shared_with_workers() as api_url:
        if params.dask_address and (note := loopback_api_note(api_url)):
            get_run_logger().warning(note)
        campaigns_flow.with_options(task_runner=runner)(
            jobs, [f"{c.scenario}-{method_of(c)}-s{c.seed}" for c in plan])
    refresh_catalog(root)
    results = add_controls(root, plan, collect_results(root, plan), params.controls)
    folder = write_experiment_report(root, results, params.report_name)
    publish("evoeye-rq2", markdown(results), f"experiment report, {folder / 'rq2.html'}")
    get_run_logger().info("experiment report: %s", folder / "rq2.html")
    return {"report_dir": str(folder), "campaigns": len(plan), "results": results}


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(ExperimentParams, experiment_flow, __doc__)
