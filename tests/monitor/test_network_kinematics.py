"""The network's kinematics option: what it derives, that it agrees with the TTC rule, that it
leaves every earlier network as it was, and that a trained version carries it to ONNX."""

from __future__ import annotations

import numpy as np
import onnxruntime as ort
import pytest
import torch

from evoeye.baselines.ttc import EGO_LENGTH_M, EGO_WIDTH_M, min_ttc_s
from evoeye.monitor.export import LOGIT, export_onnx
from evoeye.monitor.kinematics import (
    KINEMATIC_FEATURES,
    MAX_INV_TTC_HZ,
    frame_kinematics,
    obstacle_kinematics,
)
from evoeye.monitor.model import INPUTS, FusionConfig, FusionNet, config_from_dict
from evoeye.monitor.registry import load_monitor
from evoeye.store import load_windows
from evoeye.store.features import PERCEPTION_FEATURES
from tests.monitor.conftest import FAST, HORIZON_S, SCENARIO
from tests.monitor.test_model import random_inputs

K = {name: i for i, name in enumerate(KINEMATIC_FEATURES)}


def obstacle(**values: float) -> torch.Tensor:
    row = torch.zeros(len(PERCEPTION_FEATURES))
    for name, value in {"length_m": 4.5, "width_m": 1.8, "cos_dheading": 1.0, **values}.items():
        row[PERCEPTION_FEATURES.index(name)] = value
    return row


def test_a_braking_lead_reads_as_its_gap_closing_speed_and_required_deceleration() -> None:
    lead = obstacle(dx_m=20.0, dvx_mps=-10.0)  # 20 m ahead, closing at 10 m/s
    k = obstacle_kinematics(lead[None])[0]
    gap = 20.0 - (EGO_LENGTH_M + 4.5) / 2
    assert k[K["gap_m"]] == pytest.approx(gap)
    assert k[K["closing_mps"]] == pytest.approx(10.0)
    assert k[K["inv_ttc_hz"]] == pytest.approx(10.0 / gap)
    assert k[K["required_decel_mps2"]] == pytest.approx(100.0 / (2 * gap))
    # the same car one lane over, drifting in at 1 m/s: no corridor TTC, a lateral approach
    side = obstacle_kinematics(obstacle(dx_m=20.0, dy_m=3.5, dvx_mps=-10.0, dvy_mps=-1.0)[None])[0]
    assert side[K["inv_ttc_hz"]] == 0 and side[K["required_decel_mps2"]] == 0
    assert side[K["lateral_inv_ttc_hz"]] == pytest.approx(1.0 / (3.5 - (EGO_WIDTH_M + 1.8) / 2))
    # opening gaps and a car behind that falls back give no approach
    for away in (obstacle(dx_m=20.0, dvx_mps=3.0), obstacle(dx_m=-20.0, dvx_mps=-3.0)):
        assert obstacle_kinematics(away[None])[0, K["inv_ttc_hz"]] == 0


def test_the_inverse_ttc_is_the_ttc_rules_ttc_inverted() -> None:
    rng = np.random.default_rng(3)
    p = np.zeros((400, 1, len(PERCEPTION_FEATURES)), dtype=np.float32)
    cols = {n: PERCEPTION_FEATURES.index(n) for n in PERCEPTION_FEATURES}
    p[..., cols["dx_m"]] = rng.uniform(-60, 60, (400, 1))
    p[..., cols["dy_m"]] = rng.uniform(-4, 4, (400, 1))
    p[..., cols["dvx_mps"]] = rng.uniform(-15, 15, (400, 1))
    p[..., cols["length_m"]], p[..., cols["width_m"]], p[..., cols["cos_dheading"]] = 4.5, 1.8, 1
    ttc = min_ttc_s(p, np.ones((400, 1), dtype=bool))
    inv = obstacle_kinematics(torch.from_numpy(p))[:, 0, K["inv_ttc_hz"]].numpy()
    gap = obstacle_kinematics(torch.from_numpy(p))[:, 0, K["gap_m"]].numpy()
    exact = np.isfinite(ttc) & (gap >= 0.5) & (inv < MAX_INV_TTC_HZ)
    assert exact.sum() > 50 and (~np.isfinite(ttc)).sum() > 50
    np.testing.assert_allclose(inv[exact], 1 / ttc[exact], rtol=1e-5)
    assert (inv[~np.isfinite(ttc)] == 0).all()  # never closing in the corridor: no TTC, 0


def test_the_frame_summary_takes_the_largest_over_the_obstacles_present() -> None:
    near, far = obstacle(dx_m=10.0, dvx_mps=-5.0), obstacle(dx_m=40.0, dvx_mps=-5.0)
    kin = obstacle_kinematics(torch.stack([far, near])[None])
    both = frame_kinematics(kin, torch.tensor([[True, True]]))
    only_far = frame_kinematics(kin, torch.tensor([[True, False]]))
    assert both[0, 0] == kin[0, 1, K["inv_ttc_hz"]] and only_far[0, 0] == kin[0, 0, K["inv_ttc_hz"]]
    assert frame_kinematics(kin, torch.tensor([[False, False]])).abs().sum() == 0


def test_the_option_is_off_by_default_and_leaves_earlier_networks_unchanged() -> None:
    plain = FusionNet(FusionConfig())
    assert "kinematics" not in plain.config.to_dict()  # same checkpoint, same version id
    assert config_from_dict(plain.config.to_dict()) == plain.config
    kin = FusionNet(FusionConfig(kinematics=True))
    assert config_from_dict(kin.config.to_dict()) == kin.config
    assert kin.n_parameters() > plain.n_parameters()
    assert set(kin.norm) == set(plain.norm) | {"kinematics"}
    # without perception there is nothing to derive it from
    assert "kinematics" not in FusionNet(FusionConfig(kinematics=True,
                                                      modules=("control",))).norm


def test_masked_obstacles_still_do_not_change_the_score() -> None:
    net = FusionNet(FusionConfig(kinematics=True)).eval()
    x = random_inputs(net)
    base = net(*x.values())
    y = {k: v.clone() for k, v in x.items()}
    y["perception"][~x["perception_mask"]] = 1e4
    torch.testing.assert_close(net(*y.values()), base, rtol=0, atol=0)
    y["perception"][x["perception_mask"]] += 5.0
    assert not torch.allclose(net(*y.values()), base)


def test_a_trained_version_carries_the_option_to_onnx(tiny, tmp_path) -> None:
    from evoeye.monitor.train import train_monitor

    version = train_monitor(tiny.root, SCENARIO, horizon_s=HORIZON_S, seed=0, kinematics=True,
                            **FAST)
    monitor = load_monitor(tiny.root, version)
    assert monitor.net.config.kinematics and monitor.card["config"]["kinematics"] is True
    # the normaliser of the derived features was fitted: not the identity it starts as
    assert not torch.equal(monitor.net.norm["kinematics"].std, torch.ones(2))
    session = ort.InferenceSession(str(export_onnx(monitor, tmp_path / "m.onnx")),
                                   providers=["CPUExecutionProvider"])
    windows = load_windows(tiny.root, context_len=5, horizon_s=HORIZON_S)
    arrays = windows.arrays(np.arange(min(len(windows), 200)))
    (logit,) = session.run([LOGIT], {name: arrays[name] for name in INPUTS})
    np.testing.assert_allclose(logit, monitor.logits(windows)[:len(logit)], rtol=1e-4,
                               atol=1e-4)


def test_the_lookahead_recipe_trains_its_own_network_on_critical_approaches(tiny) -> None:
    from evoeye.monitor.train import train_monitor

    version = train_monitor(tiny.root, SCENARIO, horizon_s=HORIZON_S, seed=0,
                            recipe="lookahead-v1", epochs=2, patience=2, batch_size=64)
    monitor = load_monitor(tiny.root, version)
    config, hyper = monitor.net.config, monitor.card["hyperparameters"]
    assert (config.context_len, config.kinematics) == (20, True)
    assert hyper["recipe"] == "lookahead-v1" and hyper["target"] == "critical"
    # the caller's choice wins over the recipe's network
    short = load_monitor(tiny.root, train_monitor(
        tiny.root, SCENARIO, horizon_s=HORIZON_S, seed=0, recipe="lookahead-v1", context_len=5,
        epochs=2, patience=2, batch_size=64))
    assert (short.net.config.context_len, short.net.config.kinematics) == (5, True)
