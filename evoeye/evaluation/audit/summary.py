"""The audit of a data root (or one scenario / batch of it): per-run checks over the logs, the
warehouse-backed checks, and the verdicts, grouped by logical scenario."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from itertools import groupby
from typing import Any

import numpy as np

from evoeye.baselines.context import context_inputs
from evoeye.evaluation.audit.attribution import AttributionSummary, summarise_attribution
from evoeye.evaluation.audit.context import ContextAuroc, context_auroc
from evoeye.evaluation.audit.runs import (
    DEFAULT_BOUNDS,
    AuditBounds,
    RunAudit,
    audit_runs,
    find_logs,
)
from evoeye.evaluation.audit.timing import ClockAuroc, CollisionTimes, clock_auroc, collision_times
from evoeye.evaluation.audit.verdicts import DEFAULT_THRESHOLDS, Thresholds, Verdict, verdicts
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, Windows, load_windows

HORIZON_S = 3.0  # the label horizon H of the clock check (Definition 1)


@dataclass
class ScenarioAudit:
    """One logical scenario's runs, its batch-level measurements and its verdicts."""

    logical_scenario: str
    runs: list[RunAudit]
    collision_times: CollisionTimes | None = None
    clock: ClockAuroc | None = None  # None: the runs are not in the warehouse
    context: ContextAuroc | None = None  # None: the runs are not in the warehouse
    attribution: AttributionSummary | None = None  # None: no run explained
    verdicts: list[Verdict] = field(default_factory=list)

    @property
    def ok_runs(self) -> int:
        return sum(r.status == "ok" for r in self.runs)

    @property
    def collided_runs(self) -> int:
        return sum(r.status == "ok" and r.collided for r in self.runs)

    @property
    def collision_rate(self) -> float:
        return self.collided_runs / self.ok_runs if self.ok_runs else 0.0

    @property
    def unreadable_runs(self) -> int:
        return sum(r.status == "unreadable" for r in self.runs)

    @property
    def kinematic_runs(self) -> int:
        return sum(r.kinematics is not None and r.kinematics.violated for r in self.runs)

    @property
    def pass_through_runs(self) -> int:
        return sum(bool(r.pass_through) for r in self.runs)

    @property
    def pop_in_actors(self) -> int:
        return sum(len(r.pop_in) for r in self.runs)

    def peak(self, name: str) -> tuple[float, str]:
        """The largest NPC peak of a kinematic quantity over the runs, and its run."""
        return max(((getattr(r.kinematics, name).value, r.scenario_id) for r in self.runs
                    if r.kinematics is not None), default=(0.0, ""))

    @property
    def failed(self) -> bool:
        return any(v.passed is False for v in self.verdicts)

    def to_dict(self) -> dict[str, Any]:
        return {
            "logical_scenario": self.logical_scenario,
            "runs": len(self.runs), "ok_runs": self.ok_runs, "unreadable_runs":
                self.unreadable_runs, "collided_runs": self.collided_runs,
            "collision_rate": self.collision_rate, "kinematic_runs": self.kinematic_runs,
            "pass_through_runs": self.pass_through_runs, "pop_in_actors": self.pop_in_actors,
            "collision_times": None if self.collision_times is None
            else self.collision_times.to_dict(),
            "clock_auroc": None if self.clock is None else self.clock.to_dict(),
            "context_auroc": None if self.context is None else self.context.to_dict(),
            "attribution": None if self.attribution is None else self.attribution.to_dict(),
            "verdicts": [v.to_dict() for v in self.verdicts],
            "per_run": [r.to_dict() for r in self.runs],
        }


def _frames(wh: Warehouse, ids: list[str]) -> Windows | None:
    """The runs' pre-collision frames (one L = 1 window each) with their labels at HORIZON_S,
    read once for the clock and the context checks; None when none is ingested."""
    if not ids:
        return None
    windows = load_windows(wh, ids, context_len=1, horizon_s=HORIZON_S)
    return windows if len(windows) else None


def _clock(w: Windows | None) -> ClockAuroc | None:
    return None if w is None else clock_auroc(w.t_s, w.label, w.scenario_id)


def _context(w: Windows | None) -> ContextAuroc | None:
    return None if w is None else context_auroc(context_inputs(w), w.label, w.scenario_id)


def _attribution(wh: Warehouse, ids: list[str]) -> AttributionSummary | None:
    if not ids:
        return None
    rows = wh.query("audit_attribution", scenario_ids=ids).to_pylist()
    return summarise_attribution(rows, len(ids))


def audit_scenario(name: str, runs: list[RunAudit], wh: Warehouse,
                   thresholds: Thresholds = DEFAULT_THRESHOLDS) -> ScenarioAudit:
    """The batch-level measurements and verdicts of one logical scenario's run audits."""
    ok = [r for r in runs if r.status == "ok"]
    collided = [r for r in ok if r.collided]
    s = ScenarioAudit(name, runs)
    s.collision_times = collision_times(np.array([r.collision_time_s for r in collided]))
    frames = _frames(wh, [r.scenario_id for r in ok])
    s.clock, s.context = _clock(frames), _context(frames)
    s.attribution = _attribution(wh, [r.scenario_id for r in collided])
    s.verdicts = verdicts(s, thresholds)
    return s


def group_by_scenario(runs: Iterable[RunAudit]) -> dict[str, list[RunAudit]]:
    """Run audits by logical scenario (sorted), each list in scenario-id order."""
    key = lambda r: r.logical_scenario  # noqa: E731
    return {k: sorted(g, key=lambda r: r.scenario_id)
            for k, g in groupby(sorted(runs, key=key), key=key)}


def audit_root(root: DataRoot, scenario: str | None = None, batch: str | None = None, *,
               workers: int = 1, bounds: AuditBounds = DEFAULT_BOUNDS,
               thresholds: Thresholds = DEFAULT_THRESHOLDS) -> list[ScenarioAudit]:
    """Audit every log of the root (or of one logical scenario and/or batch); read-only."""
    runs = list(audit_runs(find_logs(root, scenario, batch), bounds, workers))
    wh = Warehouse(root)
    return [audit_scenario(name, group, wh, thresholds)
            for name, group in group_by_scenario(runs).items()]
