"""The one interface every runtime monitor implements: windows in, risk scores in [0, 1] out."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from evoeye.store.windows import Windows

TARGET_FPRS = (0.05, 0.01)  # the paper's two operating points, calibrated on validation
# a warning: this many consecutive alarm frames (0.15 s at 20 Hz), wherever a run's alarms are
# read — `evoeye replay`, the reports' headline and the demo's summary
WARNING_K = 3


@dataclass(frozen=True)
class Thresholds:
    """Alarm thresholds per target false-positive rate, chosen on a validation split.

    `realised_fpr` is the FPR each threshold gives on the split it was chosen on (absent for
    thresholds saved before it was recorded). A target in `unreachable` could not be met with
    any alarm on that split (`evoeye.monitor.calibration`): its threshold is kept, but what it
    scores is no measurement of that operating point.
    """

    by_fpr: dict[float, float] = field(default_factory=dict)
    realised_fpr: dict[float, float] = field(default_factory=dict)
    unreachable: frozenset[float] = frozenset()

    def at(self, fpr: float) -> float:
        try:
            return self.by_fpr[fpr]
        except KeyError:
            have = sorted(self.by_fpr)
            raise KeyError(f"no threshold calibrated for FPR {fpr}; have {have}") from None

    def reachable(self, fpr: float) -> bool:
        """Whether the target `fpr` was met with alarms on the calibration split."""
        self.at(fpr)  # a clear error for a target never calibrated
        return fpr not in self.unreachable


@runtime_checkable
class Monitor(Protocol):
    """A runtime monitor G: a context c_t ↦ risk that the ego collides within H seconds."""

    name: str  # e.g. "fusion", "ttc", "ttc-2d", "rss", "aem", "context-only"
    version: str  # identifies the trained artefact (a content hash, or "rule" for TTC/RSS)

    def score(self, windows: Windows) -> np.ndarray:
        """(B,) float risk scores in [0, 1], one per window, higher = riskier."""
        ...
