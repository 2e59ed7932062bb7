"""Batches of runs: plan concrete scenarios, simulate each, write its MCAP log, summarise.

A run's log path is a function of (logical scenario, batch, scenario id), and logs are written
atomically, so a batch can be killed at any point and re-run: finished runs are skipped, an
unfinished one (a `.tmp` file) is simulated again, and the `.tmp` files of writers that are gone
are removed first. Workers die with the parent process that started them; Ctrl-C stops them at
once, and the runs in progress leave no file behind (`BatchInterrupted`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evoeye.ads.profiles import DEFAULT_PROFILE
from evoeye.atomic import remove_stale_temps
from evoeye.lifeline import pool_context, stop_workers, stoppable, stoppable_worker
from evoeye.log import LogError, read_run, write_episode
from evoeye.paths import DataRoot, check_batch_name
from evoeye.scenarios import get_scenario
from evoeye.sim.episode import STATUS_OK, Episode, RunSpec
from evoeye.sim.lockstep import DEFAULT_BATCH, batch_size, chunks, run_indexed
from evoeye.sim.runner import run_episode, run_spec
from evoeye.sim.worlds import DEFAULT_WORLD

DEFAULT_LOCKSTEP = DEFAULT_BATCH  # what a large draw passes as `run_batch(lockstep=…)`


def plan_uniform(
    scenario: str, n: int, seed: int, *, batch: str | None = None, source: str = "uniform",
    round: int = 0, ads: str = DEFAULT_PROFILE, world: str = DEFAULT_WORLD,
) -> list[RunSpec]:
    """n concrete scenarios drawn uniformly, each with its own run seed; all fixed by `seed`
    (the same vectors and run seeds under every ADS profile `ads` and world variant `world`)."""
    if n < 1:
        raise ValueError(f"--n must be at least 1, got {n}")
    if seed < 0:
        raise ValueError(f"--seed must be non-negative, got {seed}")
    space = get_scenario(scenario)
    variant = "".join(f"{v}-" for v, default in ((ads, DEFAULT_PROFILE), (world, DEFAULT_WORLD))
                      if v != default)
    batch = check_batch_name(batch or f"{source}-{variant}seed{seed}")
    xs = space.sample(np.random.default_rng(seed), n)
    run_seeds = np.random.SeedSequence(seed).generate_state(n)
    return [
        run_spec(scenario, x, int(s), batch=batch, source=source, round=round, ads=ads,
                 world=world)
        for x, s in zip(xs, run_seeds, strict=True)
    ]


@dataclass(frozen=True)
class RunResult:
    """What happened to one planned run."""

    scenario_id: str
    path: str
    status: str  # "ok" / "failed" (the run itself) / "error" (could not simulate or write)
    collided: bool = False
    reason: str = ""
    skipped: bool = False  # already on disk
    sim_time_s: float = 0.0
    logged: bool = True  # its log is at `path` (False: simulated for its outcome only)


def simulate_and_log(spec: RunSpec, root: DataRoot, collisions_only: bool = False) -> RunResult:
    """Simulate one run and write its log, unless its log already exists (with
    `collisions_only`, only a colliding run's log is written). Picklable."""
    return simulate_and_keep(spec, root, collisions_only)[0]


def simulate_and_keep(spec: RunSpec, root: DataRoot,
                      collisions_only: bool = False) -> tuple[RunResult, Episode | None]:
    """`simulate_and_log`, and the Episode it simulated (None when the log was on disk), for a
    caller that converts the run in memory (`evoeye.store.log_windows.episode_run`)."""
    on_disk = logged_result(spec, root)
    if on_disk is not None:
        return on_disk, None
    episode = run_episode(spec)
    return keep(episode, root, collisions_only), episode


def simulate_and_keep_all(specs: Sequence[RunSpec], root: DataRoot,
                          collisions_only: bool = False,
                          ) -> list[tuple[RunResult, Episode | None]]:
    """`simulate_and_keep` for runs of one logical scenario, ADS profile and world, stepped
    together by the lockstep engine (`evoeye.sim.lockstep`): the same logs, bit for bit. In the
    order given. A log that cannot be written is that run's error; the others are kept."""
    out: list[tuple[RunResult, Episode | None] | None] = []
    todo = []
    for spec in specs:
        on_disk = logged_result(spec, root)
        out.append(None if on_disk is None else (on_disk, None))
        if on_disk is None:
            todo.append(spec)
    at = [i for i, o in enumerate(out) if o is None]
    for i, episode in run_indexed(todo, size=max(len(todo), 1)):
        try:
            kept = (keep(episode, root, collisions_only), episode)
        except Exception as exc:  # noqa: BLE001 - reported per run, the chunk goes on
            kept = (_error(episode.spec, root, exc), None)
        out[at[i]] = kept
    return out  # type: ignore[return-value]


def simulate_chunk(specs: Sequence[RunSpec], root: DataRoot,
                   collisions_only: bool = False) -> list[RunResult]:
    """`simulate_and_log` for runs stepped together (`simulate_and_keep_all`). Picklable."""
    return [result for result, _ in simulate_and_keep_all(specs, root, collisions_only)]


def logged_result(spec: RunSpec, root: DataRoot) -> RunResult | None:
    """The result of a run whose log is on disk (None: to be simulated; a final-named log
    that does not read back is removed, to be simulated again)."""
    path = root.run_log(spec.scenario, spec.batch, spec.scenario_id)
    if not path.exists():
        return None
    try:
        meta = read_run(path, topics=()).metadata
    except LogError:
        path.unlink()
        return None
    return RunResult(
        spec.scenario_id, str(path), meta["status"], bool(meta["collided"]),
        meta.get("reason") or "", skipped=True, sim_time_s=float(meta["duration_s"]),
    )


def keep(episode: Episode, root: DataRoot, collisions_only: bool = False) -> RunResult:
    """Write a simulated run's log (with `collisions_only`, only if it collided); its result."""
    spec, o = episode.spec, episode.outcome
    path = root.run_log(spec.scenario, spec.batch, spec.scenario_id)
    logged = not collisions_only or (o.status == STATUS_OK and o.collided)
    if logged:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_episode(episode, path)
    return RunResult(spec.scenario_id, str(path), o.status, o.collided, o.reason,
                     sim_time_s=o.duration_s, logged=logged)


def remove_stale_logs(specs: Sequence[RunSpec], root: DataRoot) -> list[Path]:
    """Check every batch name, then remove the `.tmp` logs of dead writers in their folders."""
    folders = {root.batch_dir(s.scenario, s.batch) for s in specs}
    return [p for folder in sorted(folders) for p in remove_stale_temps(folder)]


@dataclass
class BatchSummary:
    results: list[RunResult] = field(default_factory=list)
    wall_s: float = 0.0
    stale_removed: list[Path] = field(default_factory=list)  # `.tmp` logs of killed writers

    @property
    def runs(self) -> int:
        return len(self.results)

    def count(self, predicate: Callable[[RunResult], bool]) -> int:
        return sum(1 for r in self.results if predicate(r))

    @property
    def collisions(self) -> int:
        return self.count(lambda r: r.status == STATUS_OK and r.collided)

    @property
    def failures(self) -> int:
        return self.count(lambda r: r.status != STATUS_OK)

    @property
    def skipped(self) -> int:
        return self.count(lambda r: r.skipped)

    @property
    def simulated_s(self) -> float:
        return sum(r.sim_time_s for r in self.results if not r.skipped)


class BatchInterrupted(KeyboardInterrupt):
    """Ctrl-C during a batch: the workers were stopped, no log is half-written, and `summary`
    holds the runs that finished (their logs are kept; a re-run skips them)."""

    def __init__(self, summary: BatchSummary, on_disk: int, planned: int) -> None:
        self.summary, self.on_disk, self.planned = summary, on_disk, planned
        super().__init__(
            f"{on_disk} of the batch's {planned} run logs are on disk, {summary.skipped} of "
            "them from before; the runs in progress were dropped, no log is half-written. Run "
            f"the same command again to simulate the other {planned - on_disk}.")


def run_batch(
    specs: Sequence[RunSpec], root: DataRoot, *, workers: int = 1,
    progress: Callable[[Iterable], Iterable] | None = None, collisions_only: bool = False,
    lockstep: int = 1,
) -> BatchSummary:
    """Run every spec (in `workers` processes); one broken run never stops the others. Ctrl-C
    stops the workers at once and raises BatchInterrupted with what finished. With
    `collisions_only`, only the colliding runs' logs are written (the others are simulated for
    their outcome: a long draw of a rare failure's stream keeps its failures, not terabytes).
    `lockstep` > 1: up to that many runs are stepped together (`evoeye.sim.lockstep`; the same
    logs), in chunks spread over the workers."""
    if workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    if lockstep < 1:
        raise ValueError(f"--lockstep must be at least 1, got {lockstep}")
    t0 = time.perf_counter()
    summary = BatchSummary(stale_removed=remove_stale_logs(specs, root))
    wrap = progress or (lambda it: it)
    size = batch_size(len(specs), workers, lockstep)
    simulate = simulate_each if lockstep == 1 else simulate_chunk
    groups = [[s] for s in specs] if lockstep == 1 else list(chunks(specs, size))
    try:
        results = (_local(simulate, groups, root, collisions_only) if workers == 1
                   else _in_pool(simulate, groups, root, workers, collisions_only))
        for result in wrap(results):
            summary.results.append(result)
    except KeyboardInterrupt:
        on_disk = sum(root.run_log(s.scenario, s.batch, s.scenario_id).exists() for s in specs)
        raise BatchInterrupted(_finish(summary, t0), on_disk, len(specs)) from None
    return _finish(summary, t0)


def simulate_each(specs: Sequence[RunSpec], root: DataRoot,
                  collisions_only: bool = False) -> list[RunResult]:
    """`simulate_and_log` for every spec, one run at a time. Picklable."""
    return [_guarded(spec, root, collisions_only) for spec in specs]


Simulate = Callable[[Sequence[RunSpec], DataRoot, bool], list[RunResult]]


def _local(simulate: Simulate, groups: list[list[RunSpec]], root: DataRoot,
           collisions_only: bool) -> Iterator[RunResult]:
    for specs in groups:
        try:
            yield from simulate(specs, root, collisions_only)
        except Exception as exc:  # noqa: BLE001 - reported per run, the batch goes on
            yield from (_error(spec, root, exc) for spec in specs)


def _in_pool(simulate: Simulate, groups: list[list[RunSpec]], root: DataRoot, workers: int,
             collisions_only: bool) -> Iterator[RunResult]:
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=pool_context(),
                               initializer=stoppable_worker, initargs=(os.getpid(),))
    try:
        futures = {pool.submit(stoppable, simulate, specs, root, collisions_only): specs
                   for specs in groups}
        for fut in as_completed(futures):
            yield from _results(fut, futures[fut], root)
    except KeyboardInterrupt:
        stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True)


def _finish(summary: BatchSummary, t0: float) -> BatchSummary:
    summary.results.sort(key=lambda r: r.scenario_id)
    summary.wall_s = time.perf_counter() - t0
    return summary


def _guarded(spec: RunSpec, root: DataRoot, collisions_only: bool = False) -> RunResult:
    try:
        return simulate_and_log(spec, root, collisions_only)
    except Exception as exc:  # noqa: BLE001 - reported per run, the batch goes on
        return _error(spec, root, exc)


def _results(fut: Future, specs: Sequence[RunSpec], root: DataRoot) -> list[RunResult]:
    try:
        result: list[RunResult] = fut.result()
    except Exception as exc:  # noqa: BLE001 - includes a worker that died
        return [_error(spec, root, exc) for spec in specs]
    return result


def _error(spec: RunSpec, root: DataRoot, exc: BaseException) -> RunResult:
    path = root.run_log(spec.scenario, spec.batch, spec.scenario_id)
    return RunResult(spec.scenario_id, str(path), "error", reason=f"{type(exc).__name__}: {exc}")
