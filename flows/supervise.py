"""Flow: `evoeye supervise` over one or more logical scenarios — calibrate the triggers, one task
per run, then the report.

A thin wrapper over `evoeye.evaluation.supervision`: a run's record is written once it is done,
so a crashed flow run started again redoes only the runs without one. The headline and the
budget tables are published as a Markdown artifact.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from prefect import flow, get_run_logger, task
from prefect.artifacts import create_markdown_artifact
from pydantic import BaseModel, Field

from evoeye.evaluation.monitors import BASELINES
from evoeye.evaluation.rq1 import trained_on
from evoeye.evaluation.supervision.batch import (
    RunJob,
    SupervisionResult,
    collect,
    plan_supervision,
)
from evoeye.evaluation.supervision.report import markdown_report, write_docs, write_report
from evoeye.evaluation.supervision.settings import LOG_POLICIES, Settings
from evoeye.evaluation.supervision.summary import BUDGETS_PER_H, summarise_supervision
from evoeye.evaluation.supervision.sweep import supervise_run
from evoeye.evaluation.supervision.triggers import (
    DEFAULT_BASELINES,
    ORACLE_LEADS_S,
    RECALLS,
    SWEEP_FPRS,
    calibrate_triggers,
    oracle_trigger,
)
from evoeye.monitor.families import load_version
from evoeye.paths import DataRoot, check_batch_name
from evoeye.scenarios import SCENARIOS
from evoeye.sim.supervisor import DEFAULT_FALLBACK, FALLBACKS, FallbackConfig, fallback_with
from evoeye.store import SplitSpec
from flows.runners import task_runner


class SuperviseParams(BaseModel):
    """What to supervise and how (validated before anything runs)."""

    root: str | None = None
    scenarios: list[str] = Field(default_factory=lambda: list(SCENARIOS))
    batch: str  # the batch of logged runs of each scenario, e.g. the Test Set's
    monitors: list[str] = Field(default_factory=list)  # trained versions, each on its scenario
    baselines: list[str] = Field(default_factory=lambda: list(DEFAULT_BASELINES))
    fprs: list[float] = Field(default_factory=lambda: list(SWEEP_FPRS))
    recalls: list[float] = Field(default_factory=lambda: list(RECALLS))
    consecutive: int = Field(1, ge=1)
    fallback_preset: str = Field(DEFAULT_FALLBACK, json_schema_extra={"enum": list(FALLBACKS)})
    decel_mps2: float | None = Field(None, gt=0.0)  # None: the preset's; the same below
    jerk_mps3: float | None = Field(None, gt=0.0)
    onset_s: float | None = Field(None, ge=0.0)
    hold_s: float | None = Field(None, ge=0.0)
    stage_decel_mps2: float | None = Field(None, ge=0.0)  # staged braking (FallbackConfig)
    stage_s: float | None = Field(None, ge=0.0)
    horizon_s: float = Field(3.0, ge=0.0)
    split_seed: int = Field(0, ge=0)
    train_frac: float = Field(0.8, ge=0.0, le=1.0)
    val_frac: float = Field(0.2, ge=0.0, le=1.0)
    test_batch: str | None = None  # default: `batch`
    logs: str = Field("collided", json_schema_extra={"enum": list(LOG_POLICIES)})
    logs_into_runs: bool = False  # True: the supervised logs are ingested as training data
    budgets: list[float] = Field(default_factory=lambda: list(BUDGETS_PER_H))
    select_batch: str | None = None  # other held-out runs the operating points are chosen on
    oracle_leads_s: list[float] = Field(default_factory=lambda: list(ORACLE_LEADS_S))
    limit: int | None = Field(None, ge=1)
    workers: int = Field(2, ge=1, le=64)
    dask_address: str | None = None
    report_name: str = "supervision"
    docs: str | None = None  # also write supervision-<scenario>.md/.svg/.json here

    @property
    def splits(self) -> SplitSpec:
        return SplitSpec(self.split_seed, self.train_frac, self.val_frac,
                         self.test_batch or self.batch)

    @property
    def fallback(self) -> FallbackConfig:
        return fallback_with(self.fallback_preset, decel_mps2=self.decel_mps2,
                             jerk_mps3=self.jerk_mps3, onset_s=self.onset_s, hold_s=self.hold_s,
                             stage_decel_mps2=self.stage_decel_mps2, stage_s=self.stage_s)

    def model_post_init(self, __context) -> None:
        check_batch_name(self.batch)
        if self.select_batch is not None:
            check_batch_name(self.select_batch)
            if self.select_batch == self.batch:
                raise ValueError("select_batch is the batch reported on: choose operating "
                                 "points on other runs")
        if self.oracle_leads_s and min(self.oracle_leads_s) <= 0:
            raise ValueError(f"oracle_leads_s must be positive, got {self.oracle_leads_s}")
        self.splits  # noqa: B018  (validates the shares and the test batch's name)
        self.fallback  # noqa: B018  (the preset's name and the values it is given)
        if unknown := [s for s in self.scenarios if s not in SCENARIOS]:
            raise ValueError(f"unknown logical scenario(s) {unknown}; known: {sorted(SCENARIOS)}")
        if unknown := [b for b in self.baselines if b not in BASELINES]:
            raise ValueError(f"unknown baseline(s) {unknown}; known: {sorted(BASELINES)}")
        if self.logs not in LOG_POLICIES:
            raise ValueError(f"logs: one of {list(LOG_POLICIES)}, got {self.logs!r}")


@task(task_run_name="calibrate-{scenario}")
def calibrate(root: DataRoot, scenario: str, params: SuperviseParams) -> Settings:
    """The scenario's triggers (its own monitor versions and the baselines), calibrated."""
    versions = [v for v in params.monitors
                if trained_on(load_version(root, v)) in (None, scenario)]
    sources = [("version", v) for v in versions] + [("baseline", b) for b in params.baselines]
    triggers = calibrate_triggers(root, scenario, sources, params.splits, params.fprs,
                                  params.horizon_s, params.recalls)
    if params.oracle_leads_s:
        triggers.append(oracle_trigger(params.oracle_leads_s))
    return Settings(scenario, params.batch, tuple(triggers), params.fallback,
                    params.consecutive, params.horizon_s, params.splits, params.logs,
                    logs_into_runs=params.logs_into_runs)


@task(retries=1, retry_delay_seconds=1, task_run_name="supervise-{job.spec.scenario_id}")
def supervise_one(job: RunJob) -> str:
    supervise_run(job)
    return job.spec.scenario_id


def supervise_batch(root: DataRoot, settings: Settings, limit: int | None
                    ) -> SupervisionResult:
    """Every run of the settings' batch not done yet, a task each."""
    plan = plan_supervision(root, settings, limit)
    futures = {supervise_one.submit(j): j for j in plan.jobs}
    errors = []
    for future, job in futures.items():
        try:
            future.result()
        except Exception as exc:  # noqa: BLE001 - reported per run, the others go on
            errors.append((job.spec.scenario_id, f"{type(exc).__name__}: {exc}"))
    return collect(settings, plan, errors)


def supervise_scenario(root: DataRoot, scenario: str, params: SuperviseParams) -> dict:
    """Calibrate, supervise every run not done yet (and the selection batch's, if given),
    summarise."""
    settings = calibrate(root, scenario, params)
    select = (None if params.select_batch is None else
              supervise_batch(root, replace(settings, batch=params.select_batch), params.limit))
    result = supervise_batch(root, settings, params.limit)
    summary = summarise_supervision(settings, result.records, tuple(params.budgets),
                                    select=select.records if select else None)
    summary["folder"] = str(result.folder)
    errors = result.errors + (select.errors if select else [])
    summary["errors"] = [{"scenario_id": s, "reason": r} for s, r in errors]
    return summary


@flow(name="evoeye-supervise", log_prints=True)
def supervise_flow(params: SuperviseParams) -> dict[str, Any]:
    """Every scenario's supervision, the report files and a Markdown artifact."""
    root = DataRoot.existing(params.root)
    summaries = [supervise_scenario(root, s, params) for s in params.scenarios]
    files = write_report(root, summaries, params.report_name)
    for summary in summaries if params.docs else []:
        write_docs(params.docs, summary)
    create_markdown_artifact(markdown=markdown_report(summaries), key="evoeye-supervision",
                             description=f"supervision report, {files.html}")
    logger = get_run_logger()
    for s in summaries:
        logger.info("%s: %d runs, %d errors; %s", s["scenario"], s["runs"], len(s["errors"]),
                    s["folder"])
    return {"summaries": summaries, "report_dir": str(files.folder)}


def supervise_batch_flow(params: SuperviseParams) -> dict[str, Any]:
    """The flow on the chosen task runner (local processes, or a Dask cluster)."""
    runner = supervise_flow.with_options(
        task_runner=task_runner(params.workers, params.dask_address))
    return runner(params)


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(SuperviseParams, supervise_batch_flow, __doc__)
