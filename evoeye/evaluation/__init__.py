"""Evaluation: the paper's metrics, scenario-level detection, lead time, reports.

Thresholds come from `evoeye.monitor.calibration` (one calibration for every monitor). Imported
on first use, so that a module of the package (a report's `table`) loads without the rest.
"""

from evoeye.lazy import lazy_attributes

_LAZY = {
    "EvaluationReport": "evoeye.evaluation.harness",
    "MonitorResult": "evoeye.evaluation.harness",
    "evaluate": "evoeye.evaluation.harness",
    "PRF": "evoeye.evaluation.metrics",
    "FrameMetrics": "evoeye.evaluation.metrics",
    "frame_metrics": "evoeye.evaluation.metrics",
    "prf": "evoeye.evaluation.metrics",
    "BASELINES": "evoeye.evaluation.monitors",
    "baseline_monitors": "evoeye.evaluation.monitors",
    "load_monitors": "evoeye.evaluation.monitors",
    "train_fusion": "evoeye.evaluation.monitors",
    "markdown_report": "evoeye.evaluation.report",
    "write_report": "evoeye.evaluation.report",
    "LeadTimes": "evoeye.evaluation.scenario",
    "Runs": "evoeye.evaluation.scenario",
    "ScenarioMetrics": "evoeye.evaluation.scenario",
    "scenario_metrics": "evoeye.evaluation.scenario",
}

__getattr__ = lazy_attributes(__name__, _LAZY)

__all__ = list(_LAZY)
