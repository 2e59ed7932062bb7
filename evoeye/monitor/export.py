"""ONNX export of a monitor version: the network plus its sigmoid, batch axis dynamic.

Inputs are named as in `evoeye.monitor.model.INPUTS`, shaped (B, L, …) like a WindowBatch
(masks are bool), and the output `risk` is (B,) in [0, 1] — the same numbers as
`FusionMonitor.score`. The TorchScript-based exporter is used (`dynamo=False`): the network is
plain tensors and control-flow-free, and this path needs no extra packages beyond `onnx`.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import torch
from torch import nn

from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import INPUTS, FusionNet, example_inputs

OPSET = 17
OUTPUT = "risk"


class _Risk(nn.Module):
    """FusionNet followed by the sigmoid, so the exported graph outputs risk scores."""

    def __init__(self, net: FusionNet):
        super().__init__()
        self.net = net

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        return torch.sigmoid(self.net(*inputs))


def export_onnx(monitor: FusionMonitor, out: str | os.PathLike) -> Path:
    """Write the monitor as an ONNX model (single file, weights embedded); the path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    model = _Risk(monitor.net).eval()
    tmp = out.with_name(f"{out.name}.{os.getpid()}.tmp")
    try:
        with warnings.catch_warnings():  # the TorchScript exporter announces its deprecation
            warnings.simplefilter("ignore", DeprecationWarning)
            torch.onnx.export(
                model, example_inputs(monitor.net), str(tmp), dynamo=False,
                input_names=list(INPUTS), output_names=[OUTPUT], opset_version=OPSET,
                dynamic_axes={name: {0: "batch"} for name in (*INPUTS, OUTPUT)},
            )
        os.replace(tmp, out)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return out
