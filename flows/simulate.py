"""Flow: simulate a batch of one logical scenario; one task per run, tasks pass file paths."""

from __future__ import annotations

from prefect import flow, get_run_logger, task
from pydantic import BaseModel, Field

from evoeye.batch import RunResult, plan_uniform, simulate_and_log
from evoeye.paths import DataRoot, check_batch_name
from evoeye.scenarios import SCENARIOS
from evoeye.sim.episode import RunSpec
from flows.runners import task_runner


class SimulateParams(BaseModel):
    """Parameters of a simulation batch (validated before anything runs)."""

    scenario: str = Field("highway-cut-in", json_schema_extra={"enum": sorted(SCENARIOS)})
    n: int = Field(10, ge=1, le=100_000)
    seed: int = Field(0, ge=0)
    root: str | None = None
    workers: int = Field(2, ge=1, le=64)
    dask_address: str | None = None
    batch: str | None = None

    def model_post_init(self, __context) -> None:
        if self.scenario not in SCENARIOS:
            known = sorted(SCENARIOS)
            raise ValueError(f"unknown logical scenario {self.scenario!r}; known: {known}")
        if self.batch is not None:
            check_batch_name(self.batch)  # a plain name: logs never leave the data root


@task(retries=1, retry_delay_seconds=1, task_run_name="run-{spec.scenario_id}")
def simulate_run(spec: RunSpec, root: DataRoot) -> RunResult:
    """Simulate and log one run (skipped if its log exists): the result names the log file."""
    return simulate_and_log(spec, root)


def simulate_batch_flow(params: SimulateParams) -> list[RunResult]:
    """Fan the batch out over the chosen task runner and collect the per-run results."""
    root = DataRoot.resolve(params.root)
    specs = plan_uniform(params.scenario, params.n, params.seed, batch=params.batch)
    runner_flow = simulate_flow.with_options(
        task_runner=task_runner(params.workers, params.dask_address)
    )
    return runner_flow(specs=specs, root=root)


@flow(name="evoeye-simulate", log_prints=True)
def simulate_flow(specs: list[RunSpec], root: DataRoot) -> list[RunResult]:
    """Simulate every spec; the results name each log (`path`) and its outcome."""
    futures = [simulate_run.submit(s, root) for s in specs]
    results = [f.result() for f in futures]
    logger = get_run_logger()
    collided = sum(r.collided for r in results)
    failed = [r for r in results if r.status != "ok"]
    logger.info("%d runs, %d collisions, %d failed; logs under %s",
                len(results), collided, len(failed), root.runs)
    for r in failed:
        logger.warning("%s %s: %s", r.status, r.scenario_id, r.reason)
    return results


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(SimulateParams, simulate_batch_flow, __doc__)
