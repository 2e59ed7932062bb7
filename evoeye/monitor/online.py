"""Any monitor online: one frame of ADS messages in, its risk score out (a supervisor's trigger).

A FusionMonitor streams through `RuntimeMonitor` — the runtime path `evoeye replay` uses (ONNX
Runtime reading fixed context buffers). Any other monitor of the `Monitor` protocol (TTC, RSS,
the AEM, the controls) scores one window of the last L frames (`WindowScorer`), laid out as
`load_windows` lays out a run's window: the first frame fills the slots before the run's start,
masked; the window carries the frame's time and the ego's position, which the context-only
control reads. A frame's features are computed once (`FrameInputs.of`, the warehouse's own
feature code) and shared by every scorer of that frame.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from evoeye.ads.messages import FrameMessages
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.protocol import Monitor
from evoeye.monitor.runtime import RuntimeMonitor
from evoeye.store.features import FEATURES, FrameFeatures, frame_features
from evoeye.store.records import MessageSignals
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S, Windows


@dataclass(frozen=True)
class FrameInputs:
    """What a monitor reads of one frame: its features (1 row), time and the ego's position."""

    features: FrameFeatures
    t_s: float
    ego_xy_m: tuple[float, float]

    @classmethod
    def of(cls, messages: FrameMessages) -> FrameInputs:
        loc = messages.localization
        return cls(frame_features(MessageSignals(messages)), float(loc.t_s),
                   (float(loc.x_m), float(loc.y_m)))


class OnlineScorer(Protocol):
    """A monitor streaming over one run: `reset()` before the run, `score` once per frame."""

    def reset(self) -> None: ...

    def score(self, frame: FrameInputs) -> float: ...


class FusionScorer:
    """A FusionMonitor through its RuntimeMonitor (scores only: the supervisor thresholds).
    Its score is the network's logit, not the risk: float32 risks saturate at 1.0 (a
    threshold there is "off"), their logits stay apart; the order is the same."""

    def __init__(self, monitor: FusionMonitor) -> None:
        self.runtime = RuntimeMonitor(monitor, threshold=1.0)

    def reset(self) -> None:
        self.runtime.reset()

    def score(self, frame: FrameInputs) -> float:
        self.runtime.step_features(frame.features, frame.t_s)
        return self.runtime.last_logit


class WindowScorer:
    """Any Monitor: the window of the last L frames, kept in a ring of L feature rows."""

    def __init__(self, monitor: Monitor, context_len: int) -> None:
        self.monitor = monitor
        self.context_len = context_len
        self._ring = FrameFeatures.empty(context_len, FEATURES)
        self._seen = 0

    def reset(self) -> None:
        self._seen = 0

    def score(self, frame: FrameInputs) -> float:
        L, k = self.context_len, self._seen
        self._ring.fill(k % L, frame.features)
        self._seen += 1
        position = np.arange(k - L + 1, k + 1)  # (L,) frames of the run, oldest first
        windows = Windows(
            self._ring, (np.maximum(position, 0) % L)[None, :], (position >= 0)[None, :],
            np.zeros(1, np.int8), np.array([""], dtype=object), np.array([k], np.int32),
            np.array([frame.t_s]), DEFAULT_HORIZON_S, FEATURES,
            np.array([frame.ego_xy_m], dtype=np.float64),
        )
        return float(np.asarray(self.monitor.score(windows)).reshape(-1)[0])


ScorerBuilder = Callable[[Monitor], OnlineScorer]
ONLINE: dict[type, ScorerBuilder] = {FusionMonitor: FusionScorer}  # the rest: WindowScorer


def online_scorer(monitor: Monitor) -> OnlineScorer:
    """The monitor as an online scorer: its family's own runtime if it has one, else a window
    of its last L frames (L: its `context_len`, as evaluation reads it)."""
    build = ONLINE.get(type(monitor))
    if build is not None:
        return build(monitor)
    return WindowScorer(monitor, int(getattr(monitor, "context_len", DEFAULT_CONTEXT_LEN)
                                     or DEFAULT_CONTEXT_LEN))
