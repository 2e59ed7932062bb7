"""`evoeye explain`: counterfactual root-cause attribution of the collision runs of a data root.

For every collision run not yet explained by this software version, re-simulate its variants
(`evoeye.sim.counterfactual`) in worker processes, as `evoeye.batch` runs simulations, and
append each run's rows to the `attribution` table as soon as it is done: re-running writes
nothing new, and a killed run resumes with the runs it had not written.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any

from evoeye import __version__
from evoeye.ads.profiles import DEFAULT_PROFILE
from evoeye.lifeline import pool_context
from evoeye.paths import DataRoot
from evoeye.sim.counterfactual import VARIANTS, Explanation, explain_run
from evoeye.sim.episode import RunSpec
from evoeye.sim.worlds import DEFAULT_WORLD
from evoeye.store import Warehouse
from evoeye.store.attribution import AttributionRow, write_attribution


def spec_of(record: dict[str, Any]) -> RunSpec:
    """The RunSpec of a stored run (a `scenarios` row or a log's metadata)."""
    return RunSpec(
        scenario=record["logical_scenario"], params=tuple(float(v) for v in record["params"]),
        seed=int(record["seed"]), scenario_id=record["scenario_id"], batch=record["batch"],
        source=record["source"], round=int(record["round"]),
        ads=record.get("ads_profile") or DEFAULT_PROFILE,
        world=record.get("world") or DEFAULT_WORLD,  # a log's (the warehouse has no column)
    )


def pending_runs(root: DataRoot, scenario: str | None = None,
                 batch: str | None = None, limit: int | None = None) -> list[RunSpec]:
    """The ingested collision runs this software version has not fully explained yet."""
    rows = Warehouse(root).query(
        "collision_runs", logical_scenario=scenario, batch=batch,
        software_version=__version__, variants=len(VARIANTS),
    ).to_pylist()
    return [spec_of(r) for r in rows[:limit]]


def rows_of(ex: Explanation, software_version: str = __version__) -> list[AttributionRow]:
    """The attribution rows of one explained run."""
    return [
        AttributionRow(ex.spec.scenario, ex.spec.scenario_id, software_version, v.variant,
                       v.collided, v.collision_time_s, v.min_distance_m, v.struck_from_behind)
        for v in ex.variants
    ]


@dataclass(frozen=True)
class Explained:
    """One run's explanation, or why there is none."""

    spec: RunSpec
    explanation: Explanation | None
    error: str = ""
    wall_s: float = 0.0


def explain_one(spec: RunSpec) -> Explained:
    """Explain one run; a run that cannot be explained is reported, never raised. Picklable."""
    t0 = time.perf_counter()
    try:
        ex = explain_run(spec)
    except Exception as exc:  # noqa: BLE001 - reported per run, the batch goes on
        return Explained(spec, None, f"{type(exc).__name__}: {exc}", time.perf_counter() - t0)
    return Explained(spec, ex, wall_s=time.perf_counter() - t0)


def _explained(specs: Sequence[RunSpec], workers: int) -> Iterator[Explained]:
    if workers == 1:
        yield from map(explain_one, specs)
        return
    with ProcessPoolExecutor(max_workers=workers, mp_context=pool_context()) as pool:
        futures = {pool.submit(explain_one, s): s for s in specs}
        for fut in as_completed(futures):
            try:
                yield fut.result()
            except Exception as exc:  # noqa: BLE001 - a worker that died
                yield Explained(futures[fut], None, f"{type(exc).__name__}: {exc}")


def explain_runs(
    root: DataRoot, specs: Sequence[RunSpec], *, workers: int = 2,
    on_result: Callable[[Explained], None] | None = None,
) -> list[Explained]:
    """Explain `specs` in `workers` processes, storing each run's rows as it finishes."""
    if workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    done: list[Explained] = []
    for e in _explained(specs, workers):
        if e.explanation is not None:
            write_attribution(root, rows_of(e.explanation))
        done.append(e)
        if on_result:
            on_result(e)
    if done:
        write_attribution(root, [], refresh_catalog=True)
    return sorted(done, key=lambda e: e.spec.scenario_id)


def attribution_shares(root: DataRoot,
                       scenario: str | None = None) -> list[dict[str, Any]]:
    """Rows of the view attribution_shares (one per logical scenario, version and cause)."""
    return Warehouse(root).query("attribution_shares", logical_scenario=scenario).to_pylist()
