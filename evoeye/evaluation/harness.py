"""`evaluate`: score a logical scenario's val and test splits with monitors and report RQ1.

Per monitor: thresholds for each target FPR are calibrated on the validation frames
(`evoeye.monitor.calibration`: the FPR they realise there is kept next to the target, and a
target no threshold can meet with any alarm is marked unreachable) and applied unchanged to the
test frames; frame-level P / R / F1, AUROC and AUPRC; scenario-level
detection for each K with warning lead times; optionally CPU latency. Every scored frame (val and
test) goes to the warehouse table monitor_scores. The windows hold no frame at or after a run's
collision (see `dataset.py`), so none enters calibration or a metric.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from evoeye.evaluation.dataset import SplitWindows, load_split, narrow
from evoeye.evaluation.latency import Latency, measure_latency
from evoeye.evaluation.metrics import Curves, FrameMetrics, frame_metrics
from evoeye.evaluation.monitors import check_scores, monitor_context_len
from evoeye.evaluation.scenario import Runs, ScenarioMetrics, scenario_metrics
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.protocol import TARGET_FPRS, WARNING_K, Monitor, Thresholds
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec
from evoeye.store.scores import ScoreRows, write_scores
from evoeye.store.windows import DEFAULT_HORIZON_S

SCENARIO_KS = (1, WARNING_K)  # the headline reads the largest: a warning


@dataclass
class MonitorResult:
    """Everything measured for one monitor on one logical scenario."""

    name: str
    version: str
    context_len: int
    thresholds: dict[float, float]  # target FPR → threshold (from validation)
    val_fpr: dict[float, float]  # FPR the thresholds realise on validation
    reachable: dict[float, bool]  # False: no threshold meets the target with any alarm on val
    frame: FrameMetrics
    scenario: dict[int, ScenarioMetrics]  # K → results
    curves: Curves
    latency: Latency | None = None
    scores_written: int = 0

    def to_dict(self) -> dict:
        return {
            "name": self.name, "version": self.version, "context_len": self.context_len,
            "thresholds": {str(k): v for k, v in self.thresholds.items()},
            "val_fpr": {str(k): v for k, v in self.val_fpr.items()},
            "reachable": {str(k): v for k, v in self.reachable.items()},
            "frame": self.frame.to_dict(),
            "scenario": {str(k): v.to_dict() for k, v in self.scenario.items()},
            "curves": asdict(self.curves),
            "latency": self.latency.to_dict() if self.latency else None,
            "scores_written": self.scores_written,
        }


@dataclass
class EvaluationReport:
    """The RQ1 figures of one logical scenario (JSON-serialisable through `to_dict`)."""

    logical_scenario: str
    splits: SplitSpec
    horizon_s: float
    fprs: tuple[float, ...]
    ks: tuple[int, ...]
    dataset: dict[str, dict[str, int]]  # split → scenarios / violations / frames / unsafe
    monitors: list[MonitorResult] = field(default_factory=list)
    frame_period_s: float | None = None  # time between two test frames of a run

    def to_dict(self) -> dict:
        return {
            "logical_scenario": self.logical_scenario, "splits": asdict(self.splits),
            "horizon_s": self.horizon_s, "fprs": list(self.fprs), "ks": list(self.ks),
            "dataset": self.dataset, "monitors": [m.to_dict() for m in self.monitors],
            "frame_period_s": self.frame_period_s,
        }


def _store(root: DataRoot, monitor: Monitor, scenario: str, parts: list[tuple[SplitWindows,
           np.ndarray]]) -> int:
    w = [p.windows for p, _ in parts]
    rows = ScoreRows(
        monitor.name, monitor.version, scenario,
        np.concatenate([x.scenario_id for x in w]), np.concatenate([x.frame for x in w]),
        np.concatenate([x.t_s for x in w]), np.concatenate([s for _, s in parts]),
    )
    return write_scores(root, rows).rows


@dataclass(frozen=True)
class Calibrated:
    """A monitor's scores of a val and a test split, and its thresholds calibrated on the val."""

    context_len: int  # the L its windows were narrowed to
    val: np.ndarray  # (B_val,) float64 in [0, 1]
    test: np.ndarray  # (B_test,) float64 in [0, 1]
    thresholds: Thresholds


def score_and_calibrate(monitor: Monitor, val: SplitWindows, test: SplitWindows,
                        fprs: Sequence[float] = TARGET_FPRS) -> Calibrated:
    """Score both splits at the monitor's own L; calibrate a threshold per target FPR on val."""
    L = monitor_context_len(monitor)
    s_val = check_scores(monitor, monitor.score(narrow(val.windows, L)), len(val))
    s_test = check_scores(monitor, monitor.score(narrow(test.windows, L)), len(test))
    return Calibrated(L, s_val, s_test, calibrate_on_validation(s_val, val.windows, fprs))


def evaluate_monitor(monitor: Monitor, val: SplitWindows, test: SplitWindows, runs: Runs, *,
                     fprs: Sequence[float] = TARGET_FPRS, ks: Sequence[int] = SCENARIO_KS,
                     latency: bool = False) -> tuple[MonitorResult, np.ndarray, np.ndarray]:
    """One monitor's results, and its raw val and test scores (for storage)."""
    c = score_and_calibrate(monitor, val, test, fprs)
    s_test, y_test, thr = c.test, test.windows.label, c.thresholds
    result = MonitorResult(
        monitor.name, monitor.version, c.context_len, dict(thr.by_fpr), dict(thr.realised_fpr),
        {f: thr.reachable(f) for f in fprs},
        frame_metrics(s_test, y_test, thr, fprs),
        {k: scenario_metrics(s_test, runs, thr, k, fprs) for k in ks},
        Curves.of(s_test, y_test),
        measure_latency(monitor, narrow(test.windows, c.context_len)) if latency else None,
    )
    return result, c.val, s_test


def evaluate(
    root: DataRoot,
    monitors: Iterable[Monitor],
    scenario: str,
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    *,
    horizon_s: float = DEFAULT_HORIZON_S,
    fprs: Sequence[float] = TARGET_FPRS,
    ks: Sequence[int] = SCENARIO_KS,
    store_scores: bool = True,
    latency: bool = False,
) -> EvaluationReport:
    """Calibrate every monitor on val, measure it on test, store its scores (module doc)."""
    monitors = list(monitors)
    if not monitors:
        raise ValueError("evaluate needs at least one monitor")
    L = max(monitor_context_len(m) for m in monitors)
    val = load_split(root, scenario, "val", splits, context_len=L, horizon_s=horizon_s)
    test = load_split(root, scenario, "test", splits, context_len=L, horizon_s=horizon_s)
    for part in (val, test):
        if len(part) == 0:
            raise ValueError(f"{scenario}: the {part.split} split has no frames; ingest more runs")
    runs = Runs.of(test.windows.scenario_id, test.windows.frame, test.windows.t_s,
                   test.collision_time_s)
    report = EvaluationReport(scenario, splits, horizon_s, tuple(fprs), tuple(ks),
                              {"val": val.stats(), "test": test.stats()},
                              frame_period_s=runs.frame_period_s or None)
    for monitor in monitors:
        result, s_val, s_test = evaluate_monitor(monitor, val, test, runs, fprs=fprs, ks=ks,
                                                 latency=latency)
        if store_scores:
            result.scores_written = _store(root, monitor, scenario, [(val, s_val), (test, s_test)])
        report.monitors.append(result)
    return report
