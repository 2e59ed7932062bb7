"""A supervision of a whole batch: its runs, one record each, resumable after a kill.

The runs are the batch's logged ones (`runs/<scenario>/<batch>/*.mcap`): the same concrete
scenarios and seeds, so every supervised run is paired with its unsupervised one. A run's record
is written atomically once all its triggers are done, so a supervision killed at any point and
started again skips the runs with a record and redoes the rest (their logs, written atomically
too, come out byte for byte the same); the `.tmp` files of killed writers are removed first.
Runs fan out over worker processes that die with the parent; one that fails is reported and the
others go on. The workers are spawned, not forked: the calling process has scored the
validation split (torch, and the context-only control's OpenMP runtime, which does not survive
a fork: forked workers died at their first run); each worker loads the triggers again from
their specs, once.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from collections.abc import Callable, Collection, Iterable
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path

import orjson

from evoeye.atomic import remove_stale_temps
from evoeye.evaluation.explain import spec_of
from evoeye.evaluation.supervision.settings import Settings, open_folder
from evoeye.evaluation.supervision.sweep import RunJob, supervise_run
from evoeye.lifeline import die_with_parent
from evoeye.log import read_run
from evoeye.paths import LOG_SUFFIX, DataRoot
from evoeye.sim.episode import RunSpec


class NoRunsError(FileNotFoundError):
    """The batch to supervise has no run logs."""


def batch_runs(root: DataRoot, scenario: str, batch: str) -> list[tuple[RunSpec, dict]]:
    """(spec, logged run metadata) of every run log of the batch, by scenario id."""
    folder = root.batch_dir(scenario, batch)
    logs = sorted(folder.glob(f"*{LOG_SUFFIX}")) if folder.is_dir() else []
    if not logs:
        raise NoRunsError(f"no run logs under {folder}: simulate the batch first "
                          f"(evoeye simulate --scenario {scenario} --batch {batch})")
    out = []
    for path in logs:
        m = read_run(path, topics=()).metadata
        out.append((spec_of(m), m))
    return out


@dataclass
class SupervisionResult:
    """The records of a supervision's runs, and what could not be done."""

    settings: Settings
    folder: Path
    records: list[dict] = field(default_factory=list)  # by scenario id
    errors: list[tuple[str, str]] = field(default_factory=list)  # (scenario id, reason)
    done_before: int = 0  # runs whose record was on disk already
    wall_s: float = 0.0
    select: SupervisionResult | None = None  # the runs operating points are chosen on


def record_path(folder: Path, scenario_id: str) -> Path:
    return folder / "runs" / f"{scenario_id}.json"


def _stale(folder: Path) -> None:
    for sub in [folder / "runs", *(p for p in (folder / "logs").glob("*") if p.is_dir())]:
        remove_stale_temps(sub)


@dataclass(frozen=True)
class Plan:
    """A supervision's folder (made), its batch's runs and the jobs of those not done yet."""

    folder: Path
    runs: list[tuple[RunSpec, dict]]
    jobs: list[RunJob]


def plan_supervision(root: DataRoot, settings: Settings, limit: int | None = None,
                     skip: int = 0, ids: Collection[str] | None = None) -> Plan:
    """Open the supervision's folder (its killed writers' `.tmp` files removed) and list the
    batch's runs (only those of `ids` if given, e.g. one split's; the first `limit`, if given,
    after the first `skip`: runs a screening has seen, left out of a confirmation) and the jobs
    of those without a record. ValueError for an id the batch does not hold."""
    if skip < 0:
        raise ValueError(f"--skip must be >= 0, got {skip}")
    runs = batch_runs(root, settings.scenario, settings.batch)
    if ids is not None:
        missing = set(ids) - {spec.scenario_id for spec, _ in runs}
        if missing:
            raise ValueError(f"{len(missing)} run(s) not in batch {settings.batch} of "
                             f"{settings.scenario}, e.g. {min(missing)}")
        runs = [(spec, m) for spec, m in runs if spec.scenario_id in ids]
    runs = runs[:limit][skip:]
    folder = open_folder(root, settings)
    _stale(folder)
    jobs = [RunJob(str(root.path), str(folder), settings, spec, meta) for spec, meta in runs
            if not record_path(folder, spec.scenario_id).exists()]
    return Plan(folder, runs, jobs)


def collect(settings: Settings, plan: Plan, errors: list[tuple[str, str]],
            wall_s: float = 0.0) -> SupervisionResult:
    """The records of the planned runs that have one (by scenario id), and the errors."""
    failed = {sid for sid, _ in errors}
    records = [orjson.loads(record_path(plan.folder, s.scenario_id).read_bytes())
               for s, _ in plan.runs if s.scenario_id not in failed]
    return SupervisionResult(settings, plan.folder, records, sorted(errors),
                             len(plan.runs) - len(plan.jobs), wall_s)


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """Spawned worker processes that die with this one (module doc); one pool can serve several
    supervisions (`run_supervision(pool=...)`), each worker loading its triggers once."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"),
                               initializer=die_with_parent, initargs=(os.getpid(),))


def run_supervision(root: DataRoot, settings: Settings, *, workers: int = 1,
                    progress: Callable[[Iterable], Iterable] | None = None,
                    limit: int | None = None, skip: int = 0,
                    ids: Collection[str] | None = None,
                    pool: Executor | None = None) -> SupervisionResult:
    """Supervise every run of the batch (of `ids`, if given; the first `limit`, if given,
    after the first `skip`) not done yet: here if `workers` is 1, else on `pool` (a
    `worker_pool`, kept open) or on a pool of `workers` made for it."""
    if workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    t0 = time.perf_counter()
    plan = plan_supervision(root, settings, limit, skip, ids)
    errors: list[tuple[str, str]] = []
    wrap = progress or (lambda it: it)
    if workers == 1:
        for job in wrap(plan.jobs):
            try:
                supervise_run(job)
            except Exception as exc:  # noqa: BLE001 - reported per run, the batch goes on
                errors.append((job.spec.scenario_id, f"{type(exc).__name__}: {exc}"))
    else:
        with nullcontext(pool) if pool is not None else worker_pool(workers) as running:
            futures: dict[Future, RunJob] = {running.submit(supervise_run, j): j
                                             for j in plan.jobs}
            for fut in wrap(as_completed(futures)):
                try:
                    fut.result()
                except Exception as exc:  # noqa: BLE001 - includes a worker that died
                    errors.append((futures[fut].spec.scenario_id,
                                   f"{type(exc).__name__}: {exc}"))
    return collect(settings, plan, errors, time.perf_counter() - t0)
