"""FusionNet: size, shapes, masks, normalisers and the input ablation."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from evoeye.monitor.inputs import parse_modules
from evoeye.monitor.model import ABLATIONS, INPUTS, FusionConfig, FusionNet, example_inputs
from evoeye.store.features import FEATURES, FrameFeatures


def random_inputs(net: FusionNet, b: int = 4, seed: int = 0) -> dict[str, torch.Tensor]:
    """Random (b, L, …) inputs with some obstacles, plan points and context slots masked."""
    g = torch.Generator().manual_seed(seed)
    out = {}
    for name, t in zip(INPUTS, example_inputs(net, b), strict=True):
        if name.endswith("mask"):
            out[name] = torch.rand(t.shape, generator=g) < 0.6
        else:
            out[name] = torch.randn(t.shape, generator=g) * 3
    out["context_mask"][:, -1] = True  # the current frame always exists
    return out


def test_parameter_count_is_about_25k_at_l5() -> None:
    n = FusionNet(FusionConfig(context_len=5)).n_parameters()
    assert 20_000 <= n <= 30_000
    # only the temporal MLP's first layer grows with L
    assert FusionNet(FusionConfig(context_len=1)).n_parameters() < n
    assert FusionNet(FusionConfig(context_len=7)).n_parameters() > n


def test_forward_gives_one_logit_per_window() -> None:
    net = FusionNet(FusionConfig(context_len=3)).eval()
    x = random_inputs(net, b=7)
    assert x["perception"].shape == (7, 3, 8, 9) and x["prediction"].shape == (7, 3, 8, 10, 2)
    out = net(*x.values())
    assert out.shape == (7,) and torch.isfinite(out).all()
    assert net.encode_frames(*list(x.values())[:-1]).shape == (7, 3, net.config.frame_dim)


def test_masked_slots_do_not_change_the_score() -> None:
    net = FusionNet(FusionConfig()).eval()
    x = random_inputs(net)
    base = net(*x.values())
    y = {k: v.clone() for k, v in x.items()}
    y["perception"][~x["perception_mask"]] = 1e4  # absent obstacles
    y["prediction"][~x["prediction_mask"]] = float("nan")
    y["plan"][~x["plan_mask"]] = -7e3  # padded plan points
    pad = ~x["context_mask"]  # padded context frames: every input of the frame
    for name in ("perception", "prediction", "plan", "plan_info", "control"):
        y[name][pad] = 123.0
    for name in ("perception_mask", "prediction_mask", "plan_mask"):
        y[name][pad] = ~y[name][pad]
    torch.testing.assert_close(net(*y.values()), base, rtol=0, atol=0)
    # … while a present obstacle does change it
    y["perception"][x["perception_mask"]] += 5.0
    assert not torch.allclose(net(*y.values()), base)


def test_a_frame_without_obstacles_or_plan_gives_a_finite_score() -> None:
    net = FusionNet(FusionConfig()).eval()
    x = random_inputs(net)
    for name in ("perception_mask", "prediction_mask", "plan_mask"):
        x[name][:] = False
    assert torch.isfinite(net(*x.values())).all()


@pytest.mark.parametrize("variant", list(ABLATIONS))
def test_ablated_inputs_have_no_encoder_and_are_ignored(variant: str) -> None:
    modules = ABLATIONS[variant]
    net = FusionNet(FusionConfig(modules=modules)).eval()
    assert set(net.encoders) == set(modules)
    x = random_inputs(net)
    base = net(*x.values())
    y = {k: v.clone() for k, v in x.items()}
    dropped = {"prediction": ["prediction"], "planning": ["plan", "plan_info"],
               "control": ["control"]}
    for module, names in dropped.items():
        if module not in modules:
            for name in names:
                y[name].normal_()
    torch.testing.assert_close(net(*y.values()), base, rtol=0, atol=0)


def test_unknown_module_or_bad_length_is_refused() -> None:
    with pytest.raises(ValueError, match="modules"):
        FusionConfig(modules=("perception", "radar"))
    with pytest.raises(ValueError, match="at least 1"):
        FusionConfig(context_len=0)


def test_normalizers_are_fitted_on_present_items_and_saved_as_buffers() -> None:
    net = FusionNet(FusionConfig())
    frames = FrameFeatures.empty(50, FEATURES)
    rng = np.random.default_rng(0)
    frames.control[:] = rng.normal(3.0, 2.0, frames.control.shape)
    frames.perception[:, :2] = rng.normal(10.0, 4.0, (50, 2, 9))
    frames.perception[:, 2:] = 1e6  # absent obstacles must not enter the statistics
    frames.perception_mask[:, :2] = True
    net.fit_normalizers(frames)
    control = net.norm["control"]
    np.testing.assert_allclose(control.mean.numpy(), frames.control.mean(0), rtol=1e-5)
    assert abs(float(net.norm["perception"].mean[0]) - 10.0) < 2.0
    assert "norm.control.mean" in net.state_dict()
    # constant features (plan here: all zeros) keep std 1 rather than dividing by zero
    assert torch.equal(net.norm["plan"].std, torch.ones_like(net.norm["plan"].std))


def test_dropout_acts_only_in_training_mode() -> None:
    net = FusionNet(FusionConfig(dropout=0.3))
    x = random_inputs(net, b=16)
    net.train()
    assert not torch.equal(net(*x.values()), net(*x.values()))
    net.eval()
    assert torch.equal(net(*x.values()), net(*x.values()))
    assert FusionNet(FusionConfig()).n_parameters() == net.n_parameters()  # no weights of its own
    with pytest.raises(ValueError, match="dropout"):
        FusionConfig(dropout=1.0)


def test_module_names_parse_from_ablation_names_or_lists() -> None:
    assert parse_modules("perception+prediction") == ("perception", "prediction")
    assert parse_modules("control, planning") == ("control", "planning")
    assert parse_modules(None) is None
    with pytest.raises(ValueError, match="lidar"):
        parse_modules("perception,lidar")


def test_forward_frames_equals_forward_on_the_gathered_windows() -> None:
    net = FusionNet(FusionConfig(context_len=3)).train()
    frames = {name: t[:, -1] for name, t in random_inputs(net, b=9, seed=2).items()
              if name != "context_mask"}  # 9 distinct frames, (9, …)
    inverse = torch.tensor([[0, 0, 1], [0, 1, 2], [6, 7, 8], [8, 8, 8]])  # (4 windows, L)
    mask = torch.tensor([[False, False, True], [True, True, True], [True] * 3,
                         [False, False, True]])
    windows = [frames[name][inverse] for name in INPUTS[:-1]]  # each window's own copies
    shared = net.forward_frames([frames[name] for name in INPUTS[:-1]], inverse, mask)
    torch.testing.assert_close(shared, net(*windows, mask), rtol=0, atol=0)
    shared.sum().backward()  # the gradient flows back through the shared frames
    assert all(p.grad is not None for p in net.parameters())
