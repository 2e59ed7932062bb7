"""Pick the task runner a flow fans out on: local processes by default, or a Dask cluster."""

from __future__ import annotations

from prefect.task_runners import ProcessPoolTaskRunner, TaskRunner


def task_runner(workers: int = 2, dask_address: str | None = None) -> TaskRunner:
    """ProcessPoolTaskRunner(workers), or DaskTaskRunner on the scheduler at `dask_address`."""
    if dask_address:
        from prefect_dask import DaskTaskRunner

        return DaskTaskRunner(address=dask_address)
    return ProcessPoolTaskRunner(max_workers=workers)
