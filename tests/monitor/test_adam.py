"""Our Adam: torch.optim.Adam's bits, without torch.optim's import of the compiler."""

from __future__ import annotations

import json
import subprocess
import sys

import torch
from torch import nn

from evoeye.monitor.adam import Adam


def _net(seed: int) -> nn.Module:
    torch.manual_seed(seed)
    return nn.Sequential(nn.Linear(7, 16), nn.ReLU(), nn.Linear(16, 3), nn.Linear(3, 1))


def test_steps_equal_torch_adam_bit_for_bit() -> None:
    ours, ref = _net(0), _net(0)
    opt_ours = Adam(ours.parameters(), lr=3e-3, weight_decay=1e-2)
    opt_ref = torch.optim.Adam(ref.parameters(), lr=3e-3, weight_decay=1e-2)
    gen = torch.Generator().manual_seed(1)
    for step in range(25):
        x = torch.randn(32, 7, generator=gen)
        for net, opt in ((ours, opt_ours), (ref, opt_ref)):
            opt.zero_grad()
            loss = net(x).square().mean()
            if step % 5 == 4:  # a step where the last layer gets no gradient: skipped, as torch
                loss = net[:3](x).square().mean()
            loss.backward()
            nn.utils.clip_grad_norm_(net.parameters(), 0.5)
            opt.step()
        for a, b in zip(ours.parameters(), ref.parameters(), strict=True):
            assert torch.equal(a, b), f"step {step}"
            assert a.grad is not None or b.grad is None
    last = list(ours.parameters())[-1]
    assert opt_ours.state[last][0].item() == opt_ref.state[list(ref.parameters())[-1]]["step"]


def test_zero_grad_drops_the_gradients() -> None:
    net = _net(0)
    opt = Adam(net.parameters())
    net(torch.ones(2, 7)).sum().backward()
    opt.zero_grad()
    assert all(p.grad is None for p in net.parameters())


TRAIN_ONE_EPOCH = """
import json, sys
import numpy as np
from evoeye.monitor.model import FusionConfig, FusionNet
from evoeye.monitor.train import TrainParams, _reproducible, fit
from evoeye.store.features import FEATURES, FrameFeatures
from evoeye.store.windows import Windows, context_rows

n = 64
features = FrameFeatures.empty(n, FEATURES)
features.control[:] = np.random.default_rng(0).normal(size=features.control.shape)
context, mask = context_rows(np.zeros(n, np.int64), 5)
label = (np.arange(n) % 4 == 0).astype(np.int8)
windows = Windows(features, context, mask, label, np.full(n, "run", dtype=object),
                  np.arange(n, dtype=np.int32), np.arange(n) / 20.0, 1.0, FEATURES)
with _reproducible(0, 1):
    fit(FusionNet(FusionConfig()), windows, windows, TrainParams(epochs=1, batch_size=16))
print(json.dumps("torch._dynamo" in sys.modules))
"""


def test_training_does_not_import_the_compiler() -> None:
    """torch.optim's wrappers would import torch._dynamo (≈ 1 s once per process)."""
    out = subprocess.run([sys.executable, "-c", TRAIN_ONE_EPOCH], capture_output=True,
                         text=True, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) is False
