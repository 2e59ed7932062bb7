"""ONNX export: ONNX Runtime gives PyTorch's scores on real windows, at any batch size."""

from __future__ import annotations

import numpy as np
import onnx
import onnxruntime as ort

from evoeye.monitor.export import LOGIT, OUTPUT, export_onnx
from evoeye.monitor.model import INPUTS
from evoeye.monitor.registry import load_monitor
from evoeye.store import load_windows


def test_onnx_runtime_and_torch_give_the_same_scores(tiny, trained, tmp_path) -> None:
    monitor = load_monitor(tiny.root, trained)
    path = export_onnx(monitor, tmp_path / "sub" / "model.onnx")
    onnx.checker.check_model(onnx.load(str(path)))
    assert not list(path.parent.glob("*.tmp"))
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    assert [i.name for i in session.get_inputs()] == list(INPUTS)
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    expected, logits = monitor.score(windows), monitor.logits(windows)
    for index in (np.arange(len(windows)), np.array([7]), np.arange(3, 120, 2)):
        arrays = windows.arrays(index)
        risk, logit = session.run([OUTPUT, LOGIT], {name: arrays[name] for name in INPUTS})
        assert risk.shape == logit.shape == (len(index),)
        np.testing.assert_allclose(risk, expected[index], rtol=0, atol=1e-5)
        np.testing.assert_allclose(logit, logits[index], rtol=1e-4, atol=1e-4)
    assert expected.std() > 0.05  # real, varied scores, not a constant
    # the logits are the risks before their sigmoid
    np.testing.assert_allclose(1 / (1 + np.exp(-logits.astype(np.float64))), expected,
                               rtol=0, atol=1e-6)


def test_the_file_says_which_version_it_is_its_thresholds_and_its_inputs(tiny, trained,
                                                                         tmp_path) -> None:
    import json

    monitor = load_monitor(tiny.root, trained)
    path = export_onnx(monitor, tmp_path / "model.onnx")
    props = {p.key: p.value for p in onnx.load(str(path)).metadata_props}
    assert props["evoeye.version"] == trained
    assert props["evoeye.logical_scenario"] == monitor.card["logical_scenario"]
    assert props["evoeye.context_len"] == "5"
    thresholds = json.loads(props["evoeye.thresholds"])
    assert thresholds == {f"{f:g}": t for f, t in monitor.thresholds.by_fpr.items()}
    spec = json.loads(props["evoeye.inputs"])
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    for given in session.get_inputs():  # the spec matches the graph, input by input
        assert spec[given.name]["shape"][1:] == given.shape[1:]
        assert spec[given.name]["dtype"] == ("bool" if given.type == "tensor(bool)"
                                             else "float32")
    assert spec[OUTPUT]["range"] == [0.0, 1.0]
    assert [o.name for o in session.get_outputs()] == [OUTPUT, LOGIT] and LOGIT in spec
