"""Runtime monitors: the FusionMonitor and the protocol every monitor implements."""

from evoeye.monitor.protocol import TARGET_FPRS, Monitor, Thresholds

__all__ = ["TARGET_FPRS", "Monitor", "Thresholds"]
