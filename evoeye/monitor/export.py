"""ONNX export of a monitor version: the network plus its sigmoid, batch axis dynamic.

Inputs are named as in `evoeye.monitor.model.INPUTS`, shaped (B, L, …) like a WindowBatch
(masks are bool), and the output `risk` is (B,) in [0, 1] — the same numbers as
`FusionMonitor.score`; `onnx_session` runs it (`RuntimeMonitor` scores with it: at batch 1
ONNX Runtime takes half the time of the traced network). The TorchScript-based exporter is
used (`dynamo=False`): the network is plain tensors and control-flow-free, and this path needs
no extra packages beyond `onnx`.
"""

from __future__ import annotations

import io
import os
import warnings
from pathlib import Path

import onnxruntime as ort
import torch
from torch import nn

from evoeye.atomic import atomic_file
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import INPUTS, FusionNet, example_inputs
from evoeye.monitor.threads import MONITOR_THREADS

OPSET = 17
OUTPUT = "risk"


class _Risk(nn.Module):
    """FusionNet followed by the sigmoid, so the exported graph outputs risk scores."""

    def __init__(self, net: FusionNet):
        super().__init__()
        self.net = net

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        return torch.sigmoid(self.net(*inputs))


def onnx_model(monitor: FusionMonitor) -> bytes:
    """The monitor as a serialised ONNX model (weights embedded), the network as it is now."""
    buffer = io.BytesIO()
    with warnings.catch_warnings():  # the TorchScript exporter announces its deprecation
        warnings.simplefilter("ignore", DeprecationWarning)
        torch.onnx.export(
            _Risk(monitor.net).eval(), example_inputs(monitor.net), buffer, dynamo=False,
            input_names=list(INPUTS), output_names=[OUTPUT], opset_version=OPSET,
            dynamic_axes={name: {0: "batch"} for name in (*INPUTS, OUTPUT)},
        )
    return buffer.getvalue()


def onnx_session(monitor: FusionMonitor, threads: int = MONITOR_THREADS) -> ort.InferenceSession:
    """ONNX Runtime running the monitor (`onnx_model`) on the CPU with `threads` threads: feed
    it arrays named as INPUTS, it returns [risk]."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = options.inter_op_num_threads = threads
    return ort.InferenceSession(onnx_model(monitor), options, providers=["CPUExecutionProvider"])


def export_onnx(monitor: FusionMonitor, out: str | os.PathLike) -> Path:
    """Write the monitor as an ONNX model (single file, weights embedded); the path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(out) as f:
        f.write(onnx_model(monitor))
    return out
