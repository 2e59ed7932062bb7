"""How flows run their tasks: the task runner they fan out on, and when a task is retried."""

from __future__ import annotations

from prefect.client.schemas.objects import TaskRun
from prefect.states import State
from prefect.task_runners import ProcessPoolTaskRunner, TaskRunner
from prefect.tasks import Task

from evoeye.store import WarehouseLockedError


def task_runner(workers: int = 2, dask_address: str | None = None) -> TaskRunner:
    """ProcessPoolTaskRunner(workers), or DaskTaskRunner on the scheduler at `dask_address`."""
    if dask_address:
        from prefect_dask import DaskTaskRunner

        return DaskTaskRunner(address=dask_address)
    return ProcessPoolTaskRunner(max_workers=workers)


def cluster_threads(dask_address: str) -> int:
    """How many tasks the Dask cluster at `dask_address` runs at once now: its workers' threads
    (what a fan-out should have work for, whatever `workers` says of local processes)."""
    from distributed import Client

    with Client(dask_address, timeout=30) as client:
        return max(1, sum(client.nthreads().values()))


def retry_while_locked(task: Task, task_run: TaskRun, state: State) -> bool:
    """Retry condition: only while another process holds the warehouse's writer lock."""
    try:
        state.result()
    except WarehouseLockedError:
        return True
    except Exception:  # noqa: BLE001  (any other failure: do not retry)
        return False
    return False
