"""The monitor in the loop: what a runtime monitor buys at run time as a safety supervisor.

`supervise` calibrates the triggers on validation (`triggers`), re-simulates a batch under every
trigger and threshold with the fallback of `evoeye.sim.supervisor` (`sweep`, `batch`), and
`summary` / `report` turn the paired records into the operating curves (collisions prevented
against false interventions per hour of safe driving) with paired bootstrap CIs.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace

from evoeye.evaluation.supervision.batch import SupervisionResult, batch_runs, run_supervision
from evoeye.evaluation.supervision.settings import Settings
from evoeye.evaluation.supervision.triggers import (
    ORACLE_LEADS_S,
    RECALLS,
    SWEEP_FPRS,
    calibrate_triggers,
    oracle_trigger,
)
from evoeye.paths import DataRoot
from evoeye.sim.supervisor import FallbackConfig
from evoeye.store import RunFilter, SplitSpec, Warehouse, select_runs
from evoeye.store.windows import DEFAULT_HORIZON_S


def supervise(root: DataRoot, scenario: str, batch: str, sources: Sequence[tuple[str, str]], *,
              splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
              fprs: Sequence[float] = SWEEP_FPRS, recalls: Sequence[float] = RECALLS,
              fallback: FallbackConfig = FallbackConfig(),  # noqa: B008 (frozen dataclass)
              consecutive: int = 1, horizon_s: float = DEFAULT_HORIZON_S,
              logs: str = "collided", logs_into_runs: bool = False, workers: int = 1,
              limit: int | None = None, skip: int = 0,
              progress: Callable[[Iterable], Iterable] | None = None,
              oracle_leads_s: Sequence[float] = ORACLE_LEADS_S,
              select_batch: str | None = None) -> SupervisionResult:
    """Calibrate the triggers (`sources`: ("version", id) or ("baseline", name)) on the
    scenario's validation split, add the oracle (at `oracle_leads_s`; none if empty), then
    supervise every run of `batch` (resuming a killed one); with `logs_into_runs` the
    supervised runs' logs go where `evoeye ingest` takes them in. With `select_batch`, its runs
    are supervised too, under the same triggers and thresholds (`.select`): the runs operating
    points are chosen on. ValueError if a run of either batch is in the train or validation
    split — a trigger must not be judged on the runs it learned or was calibrated on — or if
    the two batches are one. `skip` leaves out the first runs of `batch` (not of the selection
    batch): a confirmation on runs no earlier look has seen."""
    check_held_out(root, scenario, batch, splits)
    if select_batch is not None:
        if select_batch == batch:
            raise ValueError(f"--select-batch {select_batch} is the batch reported on: choose "
                             "operating points on other runs")
        check_held_out(root, scenario, select_batch, splits)
    triggers = calibrate_triggers(root, scenario, sources, splits, fprs, horizon_s, recalls)
    if oracle_leads_s:
        triggers.append(oracle_trigger(oracle_leads_s))
    settings = Settings(scenario, batch, tuple(triggers), fallback, consecutive, horizon_s,
                        splits, logs, logs_into_runs=logs_into_runs)
    select = None if select_batch is None else run_supervision(
        root, replace(settings, batch=select_batch), workers=workers, progress=progress,
        limit=limit)
    result = run_supervision(root, settings, workers=workers, progress=progress, limit=limit,
                             skip=skip)
    return replace(result, select=select)


def check_held_out(root: DataRoot, scenario: str, batch: str, splits: SplitSpec) -> None:
    """ValueError naming how many of the batch's runs the train and val splits hold."""
    ids = {spec.scenario_id for spec, _ in batch_runs(root, scenario, batch)}
    con = Warehouse(root).connect()
    try:
        seen = {split: ids & set(select_runs(con, RunFilter(scenario, split, splits=splits))
                                 .column("scenario_id").to_pylist())
                for split in ("train", "val")}
    finally:
        con.close()
    if any(seen.values()):
        raise ValueError(f"{' and '.join(f'{len(v)} runs in {k}' for k, v in seen.items() if v)}"
                         f": batch {batch} is not held out under split {splits}; give it as "
                         "the test batch (--test-batch) or supervise another batch")


__all__ = ["Settings", "SupervisionResult", "run_supervision", "supervise"]
