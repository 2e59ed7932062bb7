"""RuntimeMonitor: the FusionMonitor inside an ADS loop — one frame of messages in, risk out.

Each frame's messages go through the warehouse's own feature code (`frame_features` of
`evoeye.store.features`, reading the messages as `MessageSignals`: the values ingest would store),
so at run time the monitor sees exactly the inputs it was trained on. The last L frames form
the context, kept in fixed (1, L, …) buffers the network reads in place; until L frames have
been seen, the first frame fills the missing slots and they are masked, exactly as
`load_windows` pads the start of a run. The network runs in ONNX Runtime (`onnx_session`,
exported on the first frame: the network as it is then), at batch 1 half the cost of the traced
network, with its scores (to float rounding). Streaming a run therefore gives the scores of its
warehouse windows.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import onnxruntime as ort

from evoeye.ads.messages import FrameMessages
from evoeye.monitor.export import LOGIT, OUTPUT, onnx_session
from evoeye.monitor.fusion import FusionMonitor
from evoeye.store.features import FrameFeatures, frame_features
from evoeye.store.records import MessageSignals


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
        self._context: dict[str, np.ndarray] = {}  # (1, L, …) per input, oldest first
        self._risk = np.zeros(1, np.float32)  # the network's output, written in place
        self._logit = np.zeros(1, np.float32)  # … and its logit (`last_logit`)
        self._session: ort.InferenceSession | None = None
        self._binding: ort.IOBinding | None = None  # the session reading the buffers above
        self._seen = 0  # frames of the current run
        self._run = 0

    def reset(self) -> None:
        """Forget the context: the next frame starts a new run."""
        self._seen = 0
        self._run = 0

    def step(self, messages: FrameMessages) -> RiskState:
        """Score the context ending at this frame (its modules' messages, in time order)."""
        features = frame_features(MessageSignals(messages))
        return self.step_features(features, float(messages.localization.t_s))

    def step_features(self, features: FrameFeatures, t_s: float) -> RiskState:
        """As `step`, from one frame's already computed features (a FrameFeatures of 1 row)."""
        if len(features) != 1:
            raise ValueError(f"one frame at a time, got {len(features)}")
        self._push(features.arrays())
        score = self._score()
        above = score > self.threshold
        self._run = self._run + 1 if above else 0
        return RiskState(t_s, score, above, self._run >= self.consecutive, self.threshold)

    def _score(self) -> float:
        """The network's risk for the context in the buffers, which ONNX Runtime reads in place
        (bound once: a call passes no arrays)."""
        if self._binding is None:
            self._session = onnx_session(self.monitor)
            self._binding = self._session.io_binding()
            for name, arr in self._context.items():
                self._binding.bind_ortvalue_input(name, ort.OrtValue.ortvalue_from_numpy(arr))
            self._binding.bind_ortvalue_output(OUTPUT, ort.OrtValue.ortvalue_from_numpy(self._risk))
            self._binding.bind_ortvalue_output(LOGIT,
                                               ort.OrtValue.ortvalue_from_numpy(self._logit))
        self._session.run_with_iobinding(self._binding)
        return float(self._risk[0])

    @property
    def last_logit(self) -> float:
        """The logit of the last frame's risk (a threshold on it does not saturate)."""
        return float(self._logit[0])

    def _push(self, frame: dict[str, np.ndarray]) -> None:
        """Shift the context one slot left and put `frame` (arrays of 1 row) last; the first
        frame of a run fills every slot, masked but its own."""
        if not self._context:
            length = self.monitor.context_len
            self._context = {name: np.zeros((1, length, *arr.shape[1:]), arr.dtype)
                             for name, arr in frame.items()}
            self._context["context_mask"] = np.zeros((1, length), bool)
        mask = self._context["context_mask"]
        for name, arr in frame.items():
            slots = self._context[name]
            if self._seen:
                slots[0, :-1] = slots[0, 1:]
                slots[0, -1] = arr[0]
            else:
                slots[0] = arr[0]
        if self._seen:
            mask[0, :-1] = mask[0, 1:]
        else:
            mask[0] = False
        mask[0, -1] = True
        self._seen += 1

    def run(self, frames: Sequence[FrameMessages]) -> list[RiskState]:
        """Reset, then step through a whole run."""
        self.reset()
        return [self.step(m) for m in frames]
