"""Evaluation: calibration, the paper's metrics, scenario-level detection, lead time, reports."""

from evoeye.evaluation.calibration import alarms, calibrate

__all__ = ["alarms", "calibrate"]
