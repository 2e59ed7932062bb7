"""Scenario-level detection and warning lead time (paper §V-RQ1).

A monitor *warns* in a run at the first frame that completes K consecutive alarms (frames
t-K+1 … t of the run all alarm; K = 1 is a single alarm). The frames are the eligible ones,
before the run's first collision (`load_windows`). A violation run with a warning is detected
(TP), without one missed (FN); a safe run with a warning is a false positive (FP). The lead time
of a detected violation is tau_col − tau_w, tau_w the time of the frame that completes the
warning. For AUROC / AUPRC over runs, a run's score is the largest score the monitor holds for
K consecutive frames (max over t of the min over t-K+1 … t): the run warns at a
threshold exactly when this score exceeds it.

False alarms are counted in the collision-free runs: every frame that completes K consecutive
alarms after a frame without one is a warning, so a run can raise several; their rate is per
hour of those runs' eligible frames. The intervals (docs/reports.md) resample or count runs.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from evoeye.evaluation.metrics import PRF, auprc, auroc, prf
from evoeye.evaluation.stats import Estimate, median_ci, proportion_ci, rate_ci
from evoeye.monitor.calibration import alarms
from evoeye.monitor.protocol import Thresholds


@dataclass(frozen=True)
class Runs:
    """Frames grouped by run: sorted by (scenario_id, frame) once, shared by every monitor."""

    order: np.ndarray  # (N,) permutation of the input frames into run order
    start: np.ndarray  # (R,) first sorted position of each run
    run_of: np.ndarray  # (N,) run index of each sorted frame
    scenario_id: np.ndarray  # (R,) str
    collision_time_s: np.ndarray  # (R,) float64, +inf if no collision
    t_s: np.ndarray  # (N,) sorted frame times

    @classmethod
    def of(cls, scenario_id: np.ndarray, frame: np.ndarray, t_s: np.ndarray,
           collision_time_s: np.ndarray) -> Runs:
        ids = np.asarray(scenario_id).astype(str)
        order = np.lexsort((np.asarray(frame), ids))
        sids = ids[order]
        new_run = np.ones(len(sids), bool)
        new_run[1:] = sids[1:] != sids[:-1]
        start = np.flatnonzero(new_run)
        return cls(order, start, np.cumsum(new_run) - 1, sids[start],
                   np.asarray(collision_time_s, float)[order][start],
                   np.asarray(t_s, float)[order])

    @property
    def violated(self) -> np.ndarray:
        return np.isfinite(self.collision_time_s)

    def __len__(self) -> int:
        return len(self.start)

    @property
    def frames(self) -> np.ndarray:
        """(R,) eligible frames of each run."""
        return np.diff(np.append(self.start, len(self.t_s)))

    @property
    def frame_period_s(self) -> float:
        """The time between two frames of a run (the median step; 0 with no such pair)."""
        same_run = self.run_of[1:] == self.run_of[:-1]
        steps = np.diff(self.t_s)[same_run]
        return float(np.median(steps)) if len(steps) else 0.0


def consecutive_counts(alarm: np.ndarray, start: np.ndarray) -> np.ndarray:
    """(N,) length of the run of consecutive alarms ending at each frame, restarting per run.

    `alarm` is in run order; `start` holds the first position of each run."""
    alarm = np.asarray(alarm, bool)
    idx = np.arange(len(alarm))
    last_reset = np.where(alarm, -1, idx)  # a frame without alarm resets the count
    last_reset[start] = np.maximum(last_reset[start], start - 1)  # so does a new run
    return idx - np.maximum.accumulate(last_reset) if len(alarm) else idx


def k_window_min(scores: np.ndarray, start: np.ndarray, k: int) -> np.ndarray:
    """(N,) min of the scores of frames t-k+1 … t of the same run; -inf for the first k-1."""
    scores = np.asarray(scores, float)
    pos = np.arange(len(scores)) - np.repeat(start, np.diff(np.append(start, len(scores))))
    out = scores.copy()
    for j in range(1, k):
        shifted = np.full_like(scores, np.inf)
        shifted[j:] = scores[:-j]
        out = np.minimum(out, shifted)
    return np.where(pos >= k - 1, out, -np.inf)


@dataclass(frozen=True)
class LeadTimes:
    """Warning lead times (s) of the detected violations."""

    detected: int
    violations: int
    values_s: list[float]
    warned_ids: list[str] = field(default_factory=list)  # the detected violation runs

    @property
    def median_s(self) -> float | None:
        return float(np.median(self.values_s)) if self.values_s else None

    @cached_property
    def recall(self) -> Estimate:
        """detected / violations with its Wilson interval over the violation runs."""
        return proportion_ci(self.detected, self.violations)

    @cached_property
    def median(self) -> Estimate:
        """The median lead time with its bootstrap interval over the detected runs."""
        return median_ci(self.values_s)

    def to_dict(self) -> dict:
        return {"detected": self.detected, "violations": self.violations,
                "median_s": self.median_s, "values_s": self.values_s,
                "warned_ids": self.warned_ids, "recall": self.recall.to_dict(),
                "median": self.median.to_dict()}


@dataclass(frozen=True)
class FalseAlarms:
    """Warnings raised in the collision-free runs, per hour of their eligible frames."""

    events: int  # warnings raised (a run may raise several)
    safe_runs: int
    alarmed_runs: int  # safe runs with at least one warning
    safe_h: float
    per_run: list[int] = field(default_factory=list)  # warnings of each safe run
    run_h: list[float] = field(default_factory=list)  # hours of each safe run

    @cached_property
    def per_h(self) -> Estimate:
        """Warnings per hour of safe driving with its bootstrap interval over safe runs."""
        return rate_ci(self.per_run, self.run_h)

    def to_dict(self) -> dict:
        return {"events": self.events, "safe_runs": self.safe_runs,
                "alarmed_runs": self.alarmed_runs, "safe_h": self.safe_h,
                "per_h": self.per_h.to_dict()}


@dataclass(frozen=True)
class ScenarioMetrics:
    """Scenario-level results for one K: per target FPR the run counts and lead times."""

    k: int
    at_fpr: dict[float, PRF]
    lead_time: dict[float, LeadTimes]
    auroc: float | None
    auprc: float | None
    scenarios: int
    violations: int
    false_alarms: dict[float, FalseAlarms] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "k": self.k,
            "at_fpr": {str(f): v.to_dict() for f, v in self.at_fpr.items()},
            "lead_time": {str(f): v.to_dict() for f, v in self.lead_time.items()},
            "false_alarms": {str(f): v.to_dict() for f, v in self.false_alarms.items()},
            "auroc": self.auroc, "auprc": self.auprc,
            "scenarios": self.scenarios, "violations": self.violations,
        }


def warnings_at(runs: Runs, alarm_sorted: np.ndarray, k: int) -> np.ndarray:
    """(R,) time of each run's first K-consecutive alarm; NaN where it never warns."""
    confirmed = consecutive_counts(alarm_sorted, runs.start) >= k
    first = np.full(len(runs), np.nan)
    hit = np.flatnonzero(confirmed)
    if len(hit):
        r, first_pos = np.unique(runs.run_of[hit], return_index=True)
        first[r] = runs.t_s[hit[first_pos]]
    return first


def false_alarms(runs: Runs, alarm_sorted: np.ndarray, k: int) -> FalseAlarms:
    """The warnings of the collision-free runs: each frame that completes K consecutive alarms
    (the count reaches K again only after a frame without alarm)."""
    raised = (consecutive_counts(alarm_sorted, runs.start) == k).astype(int)
    per_run = np.add.reduceat(raised, runs.start) if len(raised) else np.zeros(0, int)
    safe = ~runs.violated
    hours = runs.frames[safe] * runs.frame_period_s / 3600.0
    events = per_run[safe]
    return FalseAlarms(int(events.sum()), int(safe.sum()), int((events > 0).sum()),
                       float(hours.sum()), events.tolist(), hours.tolist())


def scenario_metrics(scores: np.ndarray, runs: Runs, thresholds: Thresholds, k: int,
                     fprs: Iterable[float] | None = None) -> ScenarioMetrics:
    """Detection of violation runs with K consecutive alarms, per calibrated threshold."""
    s = np.asarray(scores, float)[runs.order]
    fprs = sorted(thresholds.by_fpr, reverse=True) if fprs is None else list(fprs)
    violated = runs.violated
    at_fpr, lead, false = {}, {}, {}
    for f in fprs:
        alarm = alarms(s, thresholds.at(f))
        warn_t = warnings_at(runs, alarm, k)
        warned = ~np.isnan(warn_t)
        at_fpr[f] = prf(warned, violated, thresholds.reachable(f))
        hit = warned & violated
        leads = runs.collision_time_s[hit] - warn_t[hit]
        lead[f] = LeadTimes(int(hit.sum()), int(violated.sum()), np.round(leads, 4).tolist(),
                            runs.scenario_id[hit].tolist())
        false[f] = false_alarms(runs, alarm, k)
    windowed = k_window_min(s, runs.start, k)
    run_score = np.maximum.reduceat(windowed, runs.start) if len(s) else np.zeros(0)
    run_score = np.where(np.isfinite(run_score), run_score, 0.0)  # runs shorter than K
    return ScenarioMetrics(k, at_fpr, lead, auroc(run_score, violated),
                           auprc(run_score, violated), len(runs), int(violated.sum()), false)
