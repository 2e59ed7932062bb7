"""Flow: simulate a batch of one logical scenario, as `evoeye simulate` does; a flow run per batch.

On this machine the batch runs in one task on the command line's own process pool
(`evoeye.batch.run_batch`: forked workers with highway-env already imported, finished logs
skipped, a broken run reported and the others kept), so the flow costs what the command costs
plus one Prefect API. With `dask_address` every chunk of up to `lockstep` runs (runs stepped
together, `evoeye.sim.lockstep`) is its own task on the Dask cluster (prefect-dask), for
batches one machine cannot carry; the chunks are small enough that every thread of the cluster
(its size when the flow starts, not `workers`) gets one. Either way the batch is idempotent: a
crashed flow run is simply run again, and skips the logs it finished. With `ingest` the new
logs then go into the warehouse, as the ingest flow puts them (a subflow run).
"""

from __future__ import annotations

from prefect import flow, get_run_logger, task
from prefect.cache_policies import NONE
from pydantic import BaseModel, Field

from evoeye.batch import BatchSummary, RunResult, plan_uniform, run_batch, simulate_chunk
from evoeye.paths import DataRoot, check_batch_name
from evoeye.scenarios import SCENARIOS
from evoeye.sim.episode import RunSpec
from evoeye.sim.lockstep import batch_size, chunks
from flows.api import shared_with_workers
from flows.ingest import IngestParams, ingest_flow
from flows.published import batch_markdown, named, publish
from flows.runners import cluster_threads, task_runner

PROGRESS_EVERY = 10  # runs between two progress lines in the flow run's log


class SimulateParams(BaseModel):
    """Parameters of a simulation batch (validated before anything runs)."""

    scenario: str = Field("highway-cut-in", json_schema_extra={"enum": sorted(SCENARIOS)})
    n: int = Field(10, ge=1, le=100_000)
    seed: int = Field(0, ge=0)
    root: str | None = None
    workers: int = Field(2, ge=1, le=64)
    lockstep: int = Field(64, ge=1, le=4096)  # runs stepped together (evoeye.sim.lockstep)
    dask_address: str | None = None
    batch: str | None = None  # default uniform-seed<seed>
    ingest: bool = False  # then ingest the new logs, as the ingest flow does (a subflow run)

    def model_post_init(self, __context) -> None:
        if self.scenario not in SCENARIOS:
            known = sorted(SCENARIOS)
            raise ValueError(f"unknown logical scenario {self.scenario!r}; known: {known}")
        if self.batch is not None:
            check_batch_name(self.batch)  # a plain name: logs never leave the data root

    @property
    def batch_name(self) -> str:
        return self.batch or f"uniform-seed{self.seed}"

    def run_name(self) -> str:
        return f"simulate-{self.scenario}-{self.batch_name}-n{self.n}"


@task(retries=1, retry_delay_seconds=1, cache_policy=NONE, task_run_name="batch-{name}")
def simulate_locally(specs: list[RunSpec], root: DataRoot, workers: int,
                     name: str, lockstep: int = 1) -> BatchSummary:
    """The whole batch on `workers` local processes, its progress in the task run's log."""
    logger = get_run_logger()
    done = 0

    def progress(results):
        nonlocal done
        for r in results:
            done += 1
            if done % PROGRESS_EVERY == 0 or done == len(specs):
                logger.info("%d / %d runs", done, len(specs))
            yield r

    return run_batch(specs, root, workers=workers, progress=progress, lockstep=lockstep)


@task(retries=1, retry_delay_seconds=1, cache_policy=NONE, task_run_name="runs-{name}")
def simulate_runs(specs: list[RunSpec], root: DataRoot, name: str) -> list[RunResult]:
    """Simulate and log runs of one scenario stepped together (skipped where their logs exist):
    the results name the log files."""
    return simulate_chunk(specs, root)


@flow(name="evoeye-simulate-dask", log_prints=True)
def fan_out_flow(specs: list[RunSpec], root: DataRoot, lockstep: int = 1) -> list[RunResult]:
    """Every chunk of up to `lockstep` runs a task on the flow's task runner (the Dask cluster
    simulate_flow picks)."""
    futures = [simulate_runs.submit(c, root, f"{c[0].scenario_id}+{len(c) - 1}")
               for c in chunks(specs, lockstep)]
    return sorted((r for f in futures for r in f.result()), key=lambda r: r.scenario_id)


@flow(name="evoeye-simulate", log_prints=True, flow_run_name=named(SimulateParams.run_name))
def simulate_batch_flow(params: SimulateParams) -> list[RunResult]:
    """Simulate the batch; the results name each log (`path`) and its outcome."""
    root = DataRoot.resolve(params.root)
    specs = plan_uniform(params.scenario, params.n, params.seed, batch=params.batch)
    root.runs.mkdir(parents=True, exist_ok=True)
    if params.dask_address:
        runner = task_runner(params.workers, params.dask_address)
        with shared_with_workers():
            # a chunk for every thread of the cluster, not for `workers` local processes
            size = batch_size(len(specs), cluster_threads(params.dask_address),
                              params.lockstep)
            summary = BatchSummary(fan_out_flow.with_options(task_runner=runner)(specs, root,
                                                                                 size))
    else:
        summary = simulate_locally(specs, root, params.workers, params.batch_name,
                                   params.lockstep)
    logger = get_run_logger()
    logger.info("%d runs, %d collisions, %d failed; logs under %s", summary.runs,
                summary.collisions, summary.failures, root.batch_dir(params.scenario,
                                                                      params.batch_name))
    for r in summary.results:
        if r.status != "ok":
            logger.warning("%s %s: %s", r.status, r.scenario_id, r.reason)
    publish("evoeye-simulate", batch_markdown(params.scenario, summary, root),
            f"{params.scenario}, batch {params.batch_name}")
    if params.ingest:
        ingest_flow(IngestParams(root=str(root.path)))
    return summary.results


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(SimulateParams, simulate_batch_flow, __doc__)
