"""FusionMonitor: a trained FusionNet behind the Monitor protocol (windows in, risks out).

`score_batch` (one batch of windows, e.g. the runtime monitor's batch of 1) runs a traced copy
of the network (TorchScript, built on first use, sharing the network's parameters): at batch 1
the eager module spends most of its ~0.3 ms in Python dispatch over ~50 sub-module calls, the
traced graph ~0.1 ms, with the same numbers. If tracing is unavailable the eager network is
used. `score` (many windows over the same frames) encodes each frame once and gathers the
windows' contexts from the encoded frames: with L = 5 every frame sits in up to 5 windows, and
the frame encoders are most of the network's work.
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import torch

from evoeye.monitor.device import pick_device
from evoeye.monitor.model import FRAME_INPUTS, INPUTS, FusionNet, example_inputs
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.threads import intra_op_threads
from evoeye.store.windows import WindowBatch, Windows

SCORE_BATCH = 8192  # windows gathered and scored at a time (bounds memory, not results)


def net_inputs(batch: WindowBatch | dict[str, torch.Tensor]) -> list[torch.Tensor]:
    """The tensors FusionNet.forward takes, in order, from a WindowBatch or a dict of tensors."""
    tensors = batch.tensors() if isinstance(batch, WindowBatch) else batch
    return [tensors[name] for name in INPUTS]


def traced(net: FusionNet) -> Callable[..., torch.Tensor]:
    """The network traced for inference (any batch size), or the network itself on failure."""
    try:
        with warnings.catch_warnings(), torch.no_grad():
            warnings.simplefilter("ignore")  # torch.jit announces its deprecation
            return torch.jit.trace(net.eval(), example_inputs(net, 1), check_trace=False)
    except Exception:  # noqa: BLE001 - a missing or failing tracer only costs speed
        return net


class FusionMonitor:
    """A trained FusionMonitor version: `score(windows)` gives (B,) risks in [0, 1]."""

    name = "fusion"

    def __init__(self, net: FusionNet, version: str, thresholds: Thresholds,
                 card: dict[str, Any] | None = None, *, trace: bool = True,
                 device: str | torch.device | None = None):
        self.net = net.eval()
        self.version = version
        self.thresholds = thresholds
        self.card = card or {}
        self.device = pick_device(device)  # where `score` runs (`score_batch`: the net's)
        self._trace = trace
        self._forward: Callable[..., torch.Tensor] | None = None
        self._device_net: FusionNet | None = None

    @property
    def context_len(self) -> int:
        """L: score windows loaded with this context length."""
        return self.net.config.context_len

    @property
    def horizon_s(self) -> float | None:
        """H the monitor was trained for (None if unknown)."""
        return self.card.get("horizon_s")

    @intra_op_threads()
    def score_batch(self, batch: WindowBatch | dict[str, torch.Tensor]) -> np.ndarray:
        """(b,) float32 risks of one batch of (b, L, …) tensors; no grad, eval mode (set at
        construction: a network being trained elsewhere must not be scored mid-step); on one
        intra-op thread (`evoeye.monitor.threads`: exact scores)."""
        if self._forward is None:
            self._forward = traced(self.net) if self._trace else self.net
        with torch.inference_mode():
            return torch.sigmoid(self._forward(*net_inputs(batch))).numpy()

    def score(self, windows: Windows) -> np.ndarray:
        """(B,) float32 risk scores, one per window, in chunks of SCORE_BATCH windows, each
        distinct frame encoded once, on the monitor's device, on one intra-op thread."""
        return self._outputs(windows, torch.sigmoid)

    def logits(self, windows: Windows) -> np.ndarray:
        """(B,) float32 logits of `score`'s risks (the same order; they do not saturate where
        float32 risks reach 1.0, so thresholds there stay apart)."""
        return self._outputs(windows, lambda logit: logit)

    @intra_op_threads()
    def _outputs(self, windows: Windows,
                 head: Callable[[torch.Tensor], torch.Tensor]) -> np.ndarray:
        if windows.context_len != self.context_len:
            raise ValueError(f"monitor {self.version} takes contexts of L = {self.context_len} "
                             f"frames; these windows have L = {windows.context_len}")
        out = np.empty(len(windows), np.float32)
        features = windows.features.arrays()
        net = self._scoring_net()
        device = next(net.parameters()).device
        with torch.inference_mode():
            for start in range(0, len(windows), SCORE_BATCH):
                index = slice(start, min(start + SCORE_BATCH, len(windows)))
                rows, inverse = windows.distinct_frames(index)
                frames = [torch.from_numpy(np.take(features[name], rows, axis=0)).to(device)
                          for name in FRAME_INPUTS]  # (U, …)
                logit = net.forward_frames(frames, torch.from_numpy(inverse).to(device),
                                           torch.from_numpy(windows.context_mask[index])
                                           .to(device))
                out[index] = head(logit).cpu().numpy()
        return out

    def _scoring_net(self) -> FusionNet:
        """The network on the device `score` runs on: the monitor's own where it already sits
        on one (a network in training) or where that is the CPU, else a copy on the device."""
        if self.device.type == "cpu" or next(self.net.parameters()).device != torch.device(
                "cpu"):
            return self.net
        if self._device_net is None:
            self._device_net = copy.deepcopy(self.net).to(self.device).eval()
        return self._device_net

    def __repr__(self) -> str:
        return f"FusionMonitor({self.version!r}, L={self.context_len})"
