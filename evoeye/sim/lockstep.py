"""The lockstep engine: B runs of one logical scenario stepped together, frame by frame.

`run_episode` (`runner.py`) steps one run; its Python loop pays the interpreter's overhead on
arrays of a few actors in every module at every frame. Here every stage of a frame — reading the
worlds, the ADS's stages (`evoeye.ads.lockstep.step_batch`), stepping the worlds
(`lockstep_world.step_worlds`) — runs once for the whole batch, as array operations over all of
its runs, and a run that ends (collided, failed, out of time) leaves the batch at once.

Every run keeps its own random streams and its own state and is recorded by the same `RunLoop`
as `run_episode`'s, so an Episode from here is the one `run_episode` returns for its spec, bit
for bit, and its log has the same bytes (tests/sim/test_lockstep.py). `run_episode` stays the
reference, and the engine for counterfactual drivers and branches.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from itertools import groupby, islice

from evoeye.ads.lockstep.stack import step_batch
from evoeye.ads.stack import ADS
from evoeye.sim.episode import Episode, RunSpec
from evoeye.sim.lockstep_world import scenes, step_worlds
from evoeye.sim.runner import RunLoop, SimConfig, run_episode

DEFAULT_BATCH = 64  # runs stepped together (BENCHMARKS.md, "lockstep")


def chunks(specs: Iterable[RunSpec], size: int = DEFAULT_BATCH) -> Iterator[list[RunSpec]]:
    """Consecutive runs of one logical scenario, ADS profile and world variant, at most `size`
    at a time (a batch shares one map, one configuration and one actor count)."""
    if size < 1:
        raise ValueError(f"a lockstep batch needs at least 1 run, got {size}")
    for _, group in groupby(specs, key=lambda s: (s.scenario, s.ads, s.world)):
        it = iter(group)
        while chunk := list(islice(it, size)):
            yield chunk


def batch_size(n_runs: int, workers: int, size: int = DEFAULT_BATCH) -> int:
    """Runs per lockstep batch when n_runs are spread over `workers`: at most `size`, and small
    enough that every worker gets a batch."""
    return max(1, min(size, -(-n_runs // workers)))


def run_lockstep(specs: Iterable[RunSpec], config: SimConfig | None = None, *,
                 size: int = DEFAULT_BATCH) -> Iterator[Episode]:
    """Simulate every spec, `size` runs at a time; each Episode is yielded as its run ends
    (within a batch, in the order the runs end). Never raises for a problem inside a run."""
    for chunk in chunks(specs, size):
        if len(chunk) == 1:  # alone: the per-run engine, the same bytes, ≈ 10 % cheaper
            yield run_episode(chunk[0], config)
        else:
            yield from _lockstep(chunk, config)


def run_indexed(specs: Sequence[RunSpec], config: SimConfig | None = None, *,
                size: int = DEFAULT_BATCH) -> Iterator[tuple[int, Episode]]:
    """`run_lockstep`, each Episode with the index of its spec in `specs` (their ids unique)."""
    index = {spec.scenario_id: i for i, spec in enumerate(specs)}
    for episode in run_lockstep(specs, config, size=size):
        yield index[episode.spec.scenario_id], episode


def _lockstep(specs: Sequence[RunSpec], config: SimConfig | None) -> Iterator[Episode]:
    runs = [RunLoop(spec, config) for spec in specs]  # a bad vector raises, as in run_episode
    for run in runs:
        try:
            run.start()
        except Exception as exc:  # noqa: BLE001 - a broken run is data
            run.fail(exc)
        if not isinstance(run.driver, ADS) and not run.done:
            raise TypeError(f"the lockstep engine drives with the ADS, not {run.driver!r}")
    going = [r for r in runs if not r.done]
    yield from (r.episode() for r in runs if r.done)
    n_frames = runs[0].n_frames if runs else 0
    for k in range(n_frames):
        if not going:
            return
        observed = _observe(going, k)
        msgs = step_batch([r.driver for r, _ in observed], [s for _, s in observed])
        stepping = []
        for (run, scene), m in zip(observed, msgs, strict=True):
            try:
                if isinstance(m, Exception):
                    raise m
                if run.record(k, scene, m):
                    stepping.append((run, m.control))
            except Exception as exc:  # noqa: BLE001 - this run ends; the others go on
                run.fail(exc)
        _step(stepping, going[0].dt)
        if k == n_frames - 1:
            for run, _ in stepping:
                run.done = True
        yield from (r.episode() for r in going if r.done)
        going = [r for r in going if not r.done]


def _observe(going: list[RunLoop], k: int) -> list:
    """(run, scene) for every going run whose world reads."""
    try:
        read = scenes([r.world for r in going])
    except Exception:  # noqa: BLE001 - read each world alone to find the one that fails
        read = [None] * len(going)
    observed = []
    for run, scene in zip(going, read, strict=True):
        try:
            observed.append((run, run.observe(k, scene)))
        except Exception as exc:  # noqa: BLE001
            run.fail(exc)
    return observed


def _step(stepping: list, dt: float) -> None:
    """Step the worlds of the runs that go on with their commands. A world whose own phases
    raise ends its run; an error in the batched array work (a bug, not a run's values: NaN does
    not raise) ends every run it stepped, since their worlds may be part-stepped."""
    if not stepping:
        return
    try:
        errors = step_worlds([r.world for r, _ in stepping],
                             [c.accel_cmd_mps2 for _, c in stepping],
                             [c.steering_rad for _, c in stepping], dt)
    except Exception as exc:  # noqa: BLE001
        errors = [exc] * len(stepping)
    for (run, _), exc in zip(stepping, errors, strict=True):
        if exc is not None:
            run.fail(exc)
