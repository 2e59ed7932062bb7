"""Runtime monitors: the FusionMonitor and the protocol every monitor implements.

    train_monitor(root, scenario=…, context_len=…, modules=…, seed=…) -> version
    calibrate_on_validation(scores, val) -> Thresholds    (one calibration for every monitor)
    load_monitor(root, version) -> FusionMonitor    (score(windows) -> (B,) risks)
    RuntimeMonitor(monitor).step(frame_messages) -> RiskState
    replay(log, monitor, out) / export_onnx(monitor, out)

Everything but the protocol is imported on first use, so importing the protocol (as the
evaluation code and the SQL-only commands do) does not load torch.
"""

from importlib import import_module
from typing import Any

from evoeye.monitor.protocol import TARGET_FPRS, Monitor, Thresholds

_LAZY = {
    "ABLATIONS": "evoeye.monitor.model",
    "MODULES": "evoeye.monitor.model",
    "FusionConfig": "evoeye.monitor.model",
    "FusionNet": "evoeye.monitor.model",
    "FusionMonitor": "evoeye.monitor.fusion",
    "alarms": "evoeye.monitor.calibration",
    "calibrate": "evoeye.monitor.calibration",
    "calibrate_on_validation": "evoeye.monitor.calibration",
    "MonitorLoadError": "evoeye.monitor.registry",
    "list_versions": "evoeye.monitor.registry",
    "load_monitor": "evoeye.monitor.registry",
    "read_card": "evoeye.monitor.registry",
    "TrainParams": "evoeye.monitor.train",
    "train_monitor": "evoeye.monitor.train",
    "RiskState": "evoeye.monitor.runtime",
    "RuntimeMonitor": "evoeye.monitor.runtime",
    "replay": "evoeye.monitor.replay",
    "export_onnx": "evoeye.monitor.export",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'evoeye.monitor' has no attribute {name!r}")


__all__ = ["TARGET_FPRS", "Monitor", "Thresholds", *_LAZY]
