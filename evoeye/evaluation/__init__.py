"""Evaluation: the paper's metrics, scenario-level detection, lead time, reports.

Thresholds come from `evoeye.monitor.calibration` (one calibration for every monitor)."""

from evoeye.evaluation.harness import EvaluationReport, MonitorResult, evaluate
from evoeye.evaluation.metrics import PRF, FrameMetrics, frame_metrics, prf
from evoeye.evaluation.monitors import BASELINES, baseline_monitors, load_monitors, train_fusion
from evoeye.evaluation.report import markdown_report, write_report
from evoeye.evaluation.scenario import LeadTimes, Runs, ScenarioMetrics, scenario_metrics

__all__ = [
    "BASELINES",
    "PRF",
    "EvaluationReport",
    "FrameMetrics",
    "LeadTimes",
    "MonitorResult",
    "Runs",
    "ScenarioMetrics",
    "baseline_monitors",
    "evaluate",
    "frame_metrics",
    "load_monitors",
    "markdown_report",
    "prf",
    "scenario_metrics",
    "train_fusion",
    "write_report",
]
