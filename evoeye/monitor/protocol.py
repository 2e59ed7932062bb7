"""The one interface every runtime monitor implements: windows in, risk scores in [0, 1] out."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from evoeye.store.windows import Windows

TARGET_FPRS = (0.05, 0.01)  # the paper's two operating points, calibrated on validation


@dataclass(frozen=True)
class Thresholds:
    """Alarm thresholds per target false-positive rate, chosen on a validation split."""

    by_fpr: dict[float, float] = field(default_factory=dict)

    def at(self, fpr: float) -> float:
        try:
            return self.by_fpr[fpr]
        except KeyError:
            have = sorted(self.by_fpr)
            raise KeyError(f"no threshold calibrated for FPR {fpr}; have {have}") from None


@runtime_checkable
class Monitor(Protocol):
    """A runtime monitor G: a context c_t ↦ risk that the ego collides within H seconds."""

    name: str  # e.g. "fusion", "ttc", "rss", "aem", "context-only"
    version: str  # identifies the trained artefact (a content hash, or "rule" for TTC/RSS)

    def score(self, windows: Windows) -> np.ndarray:
        """(B,) float risk scores in [0, 1], one per window, higher = riskier."""
        ...
