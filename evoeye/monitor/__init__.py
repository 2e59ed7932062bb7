"""Runtime monitors: the FusionMonitor and the protocol every monitor implements.

    train_monitor(root, scenario=…, context_len=…, modules=…, seed=…, recipe=…) -> version
    train_monitors(root, scenario=…, seeds=[…], …) -> versions    (the same, data loaded once)
    calibrate_on_validation(scores, val) -> Thresholds    (one calibration for every monitor)
    load_monitor(root, version) -> FusionMonitor    (score(windows) -> (B,) risks)
    RuntimeMonitor(monitor).step(frame_messages) -> RiskState
    replay(log, monitor, out) / export_onnx(monitor, out)
    load_version(root, version) -> any family's version (FAMILIES: the family registry)

Everything but the protocol is imported on first use, so importing the protocol (as the
evaluation code and the SQL-only commands do) does not load torch.
"""

from evoeye.lazy import lazy_attributes
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
    "FAMILIES": "evoeye.monitor.families",
    "MonitorFamily": "evoeye.monitor.families",
    "MonitorLoadError": "evoeye.monitor.families",
    "load_version": "evoeye.monitor.families",
    "register_family": "evoeye.monitor.families",
    "list_versions": "evoeye.monitor.registry",
    "load_monitor": "evoeye.monitor.registry",
    "read_card": "evoeye.monitor.registry",
    "TrainParams": "evoeye.monitor.train",
    "train_monitor": "evoeye.monitor.train",
    "train_monitors": "evoeye.monitor.train",
    "RECIPES": "evoeye.monitor.recipes",
    "RiskState": "evoeye.monitor.runtime",
    "RuntimeMonitor": "evoeye.monitor.runtime",
    "replay": "evoeye.monitor.replay",
    "export_onnx": "evoeye.monitor.export",
}


__getattr__ = lazy_attributes(__name__, _LAZY)


__all__ = ["TARGET_FPRS", "Monitor", "Thresholds", *_LAZY]
