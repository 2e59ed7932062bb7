"""The per-run checks over many logs: find them, read each one's ground truth, check it.

Each log is read and checked in a worker process (reading is most of the cost); only the small
per-run results travel back.
"""

from __future__ import annotations

import multiprocessing as mp
from collections import Counter
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from evoeye.evaluation.audit.appearance import POP_IN_RADIUS_M, Appearance, check_pop_in
from evoeye.evaluation.audit.kinematics import KinematicBounds, KinematicResult, check_kinematics
from evoeye.evaluation.audit.overlaps import MIN_OVERLAP_S, PassThrough, check_overlaps
from evoeye.evaluation.audit.tracks import read_ground_truth
from evoeye.log.reader import LogError
from evoeye.paths import LOG_SUFFIX, DataRoot


@dataclass(frozen=True)
class AuditBounds:
    """Every per-run bound of the audit."""

    kinematics: KinematicBounds = field(default_factory=KinematicBounds)
    min_overlap_s: float = MIN_OVERLAP_S
    pop_in_radius_m: float = POP_IN_RADIUS_M


@dataclass(frozen=True)
class RunAudit:
    """One run's record and the findings of every per-run check (none if unreadable)."""

    path: str
    scenario_id: str
    logical_scenario: str
    batch: str
    status: str  # 'ok' / 'failed' from the run record; 'unreadable' when the log is not
    collided: bool
    collision_time_s: float | None
    kinematics: KinematicResult | None
    pass_through: tuple[PassThrough, ...] = ()
    pop_in: tuple[Appearance, ...] = ()
    error: str = ""

    def to_dict(self) -> dict[str, Any]:
        k = self.kinematics
        return {
            "scenario_id": self.scenario_id, "batch": self.batch, "path": self.path,
            "status": self.status, "collided": self.collided,
            "collision_time_s": self.collision_time_s, "error": self.error,
            "kinematics": None if k is None else {
                "a_lat_mps2": k.a_lat.to_dict(), "a_lon_mps2": k.a_lon.to_dict(),
                "lat_speed_mps": k.lat_speed.to_dict(), "exceeded": list(k.exceeded)},
            "pass_through": [p.to_dict() for p in self.pass_through],
            "pop_in": [a.to_dict() for a in self.pop_in],
        }


DEFAULT_BOUNDS = AuditBounds()


class NoLogsError(LookupError):
    """No finished run log under the data root matches the logical scenario and batch asked for."""


def find_logs(root: DataRoot, scenario: str | None = None, batch: str | None = None
              ) -> list[Path]:
    """Every finished log under runs/<scenario>/<batch>/, sorted (None: every one);
    NoLogsError, naming the batches the root does hold, when there is none."""
    pattern = f"{scenario or '*'}/{batch or '*'}/*{LOG_SUFFIX}"
    logs = sorted(root.runs.glob(pattern))
    if not logs:
        asked = " and ".join(f"{what} {name!r}" for what, name in (
            ("logical scenario", scenario), ("batch", batch)) if name is not None)
        held = Counter(f"{p.parent.parent.name}/{p.parent.name}"
                       for p in root.runs.glob(f"*/*/*{LOG_SUFFIX}"))
        raise NoLogsError(f"no run logs {f'of {asked} ' if asked else ''}under {root.runs}; "
                          + ("it holds " + ", ".join(f"{k} ({n} logs)" for k, n in
                                                     sorted(held.items()))
                             if held else "it holds none"))
    return logs


def audit_run(path: str | Path, bounds: AuditBounds = AuditBounds()) -> RunAudit:
    """Read one log's ground truth and run every per-run check on it."""
    path = Path(path)
    try:
        run = read_ground_truth(path)
    except LogError as exc:
        return RunAudit(str(path), path.stem, path.parent.parent.name, path.parent.name,
                        "unreadable", False, None, None, error=str(exc))
    meta, tracks = run.metadata, run.tracks
    rate_hz = meta["rate_hz"]
    return RunAudit(
        path=str(path), scenario_id=meta["scenario_id"],
        logical_scenario=meta["logical_scenario"], batch=meta["batch"],
        status=meta["status"], collided=meta["collided"],
        collision_time_s=meta["collision_time_s"],
        kinematics=check_kinematics(tracks, run.lanes, rate_hz, bounds.kinematics),
        pass_through=check_overlaps(tracks, rate_hz, bounds.min_overlap_s),
        pop_in=check_pop_in(tracks, bounds.pop_in_radius_m),
    )


def _context() -> mp.context.BaseContext:
    return mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")


def audit_runs(paths: list[Path], bounds: AuditBounds = AuditBounds(), workers: int = 1
               ) -> Iterator[RunAudit]:
    """audit_run over every path, in `workers` processes, in path order."""
    if workers <= 1 or len(paths) < 2:
        yield from (audit_run(p, bounds) for p in paths)
        return
    chunk = max(1, len(paths) // (8 * workers))
    with ProcessPoolExecutor(max_workers=workers, mp_context=_context()) as pool:
        yield from pool.map(audit_run, paths, [bounds] * len(paths), chunksize=chunk)
