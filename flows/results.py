"""Flow: `evoeye results` — the data, then each (scenario, part) as a task, then the files.

A thin wrapper over `evoeye.results`: every training, evaluation and campaign is a ledger unit
or a resumable campaign, so a crashed flow run is simply started again and redoes nothing that
finished. The findings are published as a Markdown artifact.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from prefect import flow, get_run_logger, task
from pydantic import BaseModel, Field

from evoeye.paths import DataRoot
from evoeye.results.config import ResultsConfig
from evoeye.results.markdown import findings_markdown
from evoeye.results.run import (
    PARTS,
    assemble,
    part_study,
    prepare_studies,
    scenario_data,
    write_results,
)
from evoeye.results.study import Study, monitor_study
from flows.published import named, publish

D = ResultsConfig()


class ResultsParams(BaseModel):
    """What `evoeye results` runs, at what size (ResultsConfig's fields; seeds as counts)."""

    root: str | None = None
    scenarios: list[str] = Field(default_factory=lambda: list(D.scenarios))
    parts: list[str] = Field(default_factory=lambda: list(D.parts))
    training_seeds: int = Field(len(D.training_seeds), ge=2)
    campaign_seeds: int = Field(len(D.campaign_seeds), ge=2)
    final_seeds: int = Field(D.final_seeds, ge=1)
    final: str = D.final  # "update" or "retrain" (ResultsConfig)
    initial_runs: int | dict[str, int] = Field(D.initial_runs)  # every scenario, or per one
    rq1_runs: int = Field(D.rq1_runs, ge=0)
    sim_seed: int = Field(D.sim_seed, ge=0)
    test_runs: int = Field(D.test_runs, ge=0)
    test_seed: int = Field(D.test_seed, ge=0)
    test_batch: str | None = None
    split_seed: int = Field(D.split_seed, ge=0)
    train_frac: float | None = Field(None, ge=0.0, le=1.0)
    val_frac: float | None = Field(None, ge=0.0, le=1.0)
    baselines: list[str] = Field(default_factory=lambda: list(D.baselines))
    context_lens: list[int] = Field(default_factory=lambda: list(D.context_lens))
    inputs: list[str] = Field(default_factory=lambda: list(D.inputs))
    methods: list[str] = Field(default_factory=lambda: list(D.methods))
    budget_s: float | None = Field(None, ge=0.0)
    n_round: int = Field(D.n_round, ge=1)
    update: str = D.update
    feedback: str = D.feedback
    epochs: int | None = Field(None, ge=1)
    patience: int | None = Field(None, ge=1)
    recipe: str = D.recipe  # the training recipe of every from-scratch monitor (ResultsConfig)
    workers: int = Field(D.workers, ge=1)
    # the sample-efficiency study (part "efficiency"): EfficiencyConfig's fields to change
    efficiency: dict[str, Any] = Field(default_factory=dict)
    report_name: str = "results"
    docs: str | None = None  # also copy the tables here (docs/results)
    readme: str | None = None  # also rewrite this README's findings section

    def run_name(self) -> str:
        return f"results-{self.report_name}-{'-'.join(self.parts)}"

    def config(self) -> ResultsConfig:
        values = self.model_dump(exclude={"root", "report_name", "docs", "readme"})
        values["training_seeds"] = tuple(range(self.training_seeds))
        values["campaign_seeds"] = tuple(range(self.campaign_seeds))
        return ResultsConfig(**values)

    def model_post_init(self, __context) -> None:
        self.config().check_names()  # every name and size checked before anything runs


@task(task_run_name="data")
def data_task(root: DataRoot, config: ResultsConfig) -> None:
    prepare_studies(root, config, print)


@task(task_run_name="{part}-{scenario}")
def part_task(root: DataRoot, config: ResultsConfig, scenario: str, part: str) -> dict:
    """One part (rq1, ablation, rq2) of one logical scenario: its per-seed figures."""
    study = Study(root, config, print)
    return PARTS[part](part_study(study, monitor_study(study), part), scenario)


@task(task_run_name="efficiency-{regime}")
def efficiency_task(root: DataRoot, config: ResultsConfig, regime: str) -> dict:
    """The sample-efficiency study on one regime: its curves and summaries."""
    from evoeye.results.efficiency.part import regime_part

    return regime_part(root, regime, config.efficiency_config, workers=config.workers,
                       say=print)


@flow(name="evoeye-results", log_prints=True,
      flow_run_name=named(lambda p: (p or ResultsParams()).run_name()))
def results_flow(params: ResultsParams | None = None) -> dict[str, Any]:
    """Run every part of every scenario, write the files, publish the findings."""
    params = params or ResultsParams()
    config, root = params.config(), DataRoot.resolve(params.root)
    study = Study(root, config)
    scenarios = {}
    if config.paper_parts:
        data_task(root, config)
        monitors = monitor_study(study)
        for scenario in config.scenarios:  # one after the other; a part's campaigns side by side
            scenarios[scenario] = scenario_data(study, monitors, scenario)
            for part in config.paper_parts:
                scenarios[scenario][part] = part_task(root, config, scenario, part)
    efficiency = None
    if "efficiency" in config.parts:
        from evoeye.results.efficiency.part import study_results

        eff = config.efficiency_config
        efficiency = study_results(eff, {r: efficiency_task(root, config, r)
                                         for r in eff.regimes})
    results = assemble(study, scenarios, efficiency)
    folder = write_results(root, results, params.report_name,
                           docs=Path(params.docs) if params.docs else None,
                           readme=Path(params.readme) if params.readme else None)
    publish("evoeye-results", findings_markdown(results["findings"], "this run"),
            str(folder / "results.html"))
    get_run_logger().info("results: %s", folder / "results.html")
    return {"report_dir": str(folder), "findings": [(f["id"], f["verdict"])
                                                    for f in results["findings"]]}


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(ResultsParams, results_flow, __doc__)
