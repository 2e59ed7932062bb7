"""ONNX export of a monitor version: the network plus its sigmoid, batch axis dynamic.

Inputs are named as in `evoeye.monitor.model.INPUTS`, shaped (B, L, …) like a WindowBatch
(masks are bool), and the outputs are `risk`, (B,) in [0, 1] — the same numbers as
`FusionMonitor.score` — and `logit`, (B,), the network's output before the sigmoid (as
`FusionMonitor.logits`: thresholds compared on it do not saturate where float32 risks reach
1.0); the exported file carries the version, its thresholds and the input
spec as metadata_props (`metadata`). `onnx_session` runs it (`RuntimeMonitor` scores with it:
at batch 1 ONNX Runtime takes half the time of the traced network). The TorchScript-based
exporter is used (`dynamo=False`): the network is plain tensors and control-flow-free, and this
path needs no extra packages beyond `onnx`.
"""

from __future__ import annotations

import io
import json
import os
import threading
import warnings
from pathlib import Path

import onnx
import onnxruntime as ort
import torch
from torch import nn

from evoeye.atomic import atomic_file
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import INPUTS, FusionNet, example_inputs
from evoeye.monitor.threads import MONITOR_THREADS

OPSET = 17
_EXPORTING = threading.Lock()
OUTPUT = "risk"
LOGIT = "logit"  # the second output


class _Risk(nn.Module):
    """FusionNet followed by the sigmoid, so the exported graph outputs risk scores (and the
    logits they come from)."""

    def __init__(self, net: FusionNet):
        super().__init__()
        self.net = net

    def forward(self, *inputs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        logit = self.net(*inputs)
        return torch.sigmoid(logit), logit


def onnx_model(monitor: FusionMonitor) -> bytes:
    """The monitor as a serialised ONNX model (weights embedded), the network as it is now.
    One export at a time per process: torch's exporter keeps global state, and two threads
    exporting at once failed ('GLOBALS.in_onnx_export must be False')."""
    buffer = io.BytesIO()
    with _EXPORTING, warnings.catch_warnings():  # the exporter announces its deprecation
        warnings.simplefilter("ignore", DeprecationWarning)
        torch.onnx.export(
            _Risk(monitor.net).eval(), example_inputs(monitor.net), buffer, dynamo=False,
            input_names=list(INPUTS), output_names=[OUTPUT, LOGIT], opset_version=OPSET,
            dynamic_axes={name: {0: "batch"} for name in (*INPUTS, OUTPUT, LOGIT)},
        )
    return buffer.getvalue()


def onnx_session(monitor: FusionMonitor, threads: int = MONITOR_THREADS) -> ort.InferenceSession:
    """ONNX Runtime running the monitor (`onnx_model`) on the CPU with `threads` threads: feed
    it arrays named as INPUTS, it returns [risk, logit]."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = options.inter_op_num_threads = threads
    return ort.InferenceSession(onnx_model(monitor), options, providers=["CPUExecutionProvider"])


def input_spec(monitor: FusionMonitor) -> dict[str, dict]:
    """Each input's shape (the batch axis as "batch") and dtype, and the output's."""
    spec = {name: {"shape": ["batch", *t.shape[1:]], "dtype": str(t.dtype).removeprefix("torch.")}
            for name, t in zip(INPUTS, example_inputs(monitor.net), strict=True)}
    return {**spec, OUTPUT: {"shape": ["batch"], "dtype": "float32", "range": [0.0, 1.0]},
            LOGIT: {"shape": ["batch"], "dtype": "float32"}}


def metadata(monitor: FusionMonitor) -> dict[str, str]:
    """What a runtime needs beside the graph, as ONNX metadata_props (string values; JSON
    where structured): the version and its provenance, the alarm thresholds per target FPR
    (an alarm: risk > threshold), and the input spec."""
    card = monitor.card
    thresholds = monitor.thresholds
    return {
        "evoeye.version": monitor.version,
        "evoeye.logical_scenario": str(card.get("logical_scenario")),
        "evoeye.parent": str(card.get("parent")),
        "evoeye.software_version": str(card.get("software_version")),
        "evoeye.context_len": str(monitor.context_len),
        "evoeye.horizon_s": str(card.get("horizon_s")),
        "evoeye.thresholds": json.dumps({f"{f:g}": t for f, t in thresholds.by_fpr.items()}),
        "evoeye.unreachable_fprs": json.dumps(sorted(thresholds.unreachable)),
        "evoeye.inputs": json.dumps(input_spec(monitor)),
        "evoeye.alarm": "risk > threshold of the chosen target FPR",
    }


def export_onnx(monitor: FusionMonitor, out: str | os.PathLike) -> Path:
    """Write the monitor as an ONNX model (single file, weights embedded, `metadata` in its
    metadata_props); the path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    model = onnx.load_from_string(onnx_model(monitor))
    onnx.helper.set_model_props(model, metadata(monitor))
    with atomic_file(out) as f:
        f.write(model.SerializeToString())
    return out
