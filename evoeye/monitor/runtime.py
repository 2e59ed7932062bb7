"""RuntimeMonitor: the FusionMonitor inside an ADS loop — one frame of messages in, risk out.

Each frame's messages go through the warehouse's own conversion (`runtime_table` → the
`frame_features` of `evoeye.store.features`), so at run time the monitor sees exactly the inputs
it was trained on. The last L frames form the context; until L frames have been seen, the first
frame fills the missing slots and they are masked, exactly as `warehouse/queries/windows.sql`
pads the start of a run. Streaming a run therefore gives the scores of its warehouse windows.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch

from evoeye.ads.messages import FrameMessages
from evoeye.monitor.fusion import FusionMonitor
from evoeye.store.features import FrameFeatures, frame_features
from evoeye.store.records import runtime_table


@dataclass(frozen=True)
class RiskState:
    """The monitor's output for one frame."""

    t_s: float
    score: float  # risk in [0, 1] that the ego collides within the horizon H
    above: bool  # score > threshold at this frame
    alarm: bool  # above for at least `consecutive` frames in a row, this one included
    threshold: float


class RuntimeMonitor:
    """Streaming FusionMonitor: `step(messages)` per ADS frame; `reset()` between runs.

    The alarm threshold is the version's calibrated threshold for `fpr` (0.05 or 0.01) unless
    `threshold` is given; `consecutive` = K frames above it raise the alarm (paper §V, K = 1, 3).
    """

    def __init__(self, monitor: FusionMonitor, *, fpr: float = 0.05,
                 threshold: float | None = None, consecutive: int = 1):
        if consecutive < 1:
            raise ValueError(f"consecutive frames K must be at least 1, got {consecutive}")
        self.monitor = monitor
        self.threshold = float(threshold if threshold is not None
                               else monitor.thresholds.at(fpr))
        self.consecutive = consecutive
        self._frames: deque[dict[str, np.ndarray]] = deque(maxlen=monitor.context_len)
        self._first: dict[str, np.ndarray] | None = None
        self._run = 0

    def reset(self) -> None:
        """Forget the context: the next frame starts a new run."""
        self._frames.clear()
        self._first = None
        self._run = 0

    def step(self, messages: FrameMessages) -> RiskState:
        """Score the context ending at this frame (its modules' messages, in time order)."""
        features = frame_features(runtime_table([messages]))
        return self.step_features(features, float(messages.localization.t_s))

    def step_features(self, features: FrameFeatures, t_s: float) -> RiskState:
        """As `step`, from one frame's already computed features (a FrameFeatures of 1 row)."""
        if len(features) != 1:
            raise ValueError(f"one frame at a time, got {len(features)}")
        frame = {name: arr[0] for name, arr in features.arrays().items()}
        if self._first is None:
            self._first = frame
        self._frames.append(frame)
        score = float(self.monitor.score_batch(self._context())[0])
        above = score > self.threshold
        self._run = self._run + 1 if above else 0
        return RiskState(t_s, score, above, self._run >= self.consecutive, self.threshold)

    def run(self, frames: Sequence[FrameMessages]) -> list[RiskState]:
        """Reset, then step through a whole run."""
        self.reset()
        return [self.step(m) for m in frames]

    def _context(self) -> dict[str, torch.Tensor]:
        """(1, L, …) tensors of the last L frames, padded on the left with the first frame."""
        length = self.monitor.context_len
        pad = length - len(self._frames)
        slots = [self._first] * pad + list(self._frames)
        out = {name: torch.from_numpy(np.stack([s[name] for s in slots])[None])
               for name in slots[0]}
        out["context_mask"] = torch.tensor([[False] * pad + [True] * len(self._frames)])
        return out
