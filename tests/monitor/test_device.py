"""Device choice: the CPU unless asked otherwise or a GPU is there; bad names are refused."""

from __future__ import annotations

import pytest
import torch

from evoeye.monitor.device import DEVICE_ENV, pick_device


def test_auto_is_a_gpu_when_torch_sees_one_else_the_cpu(monkeypatch) -> None:
    monkeypatch.delenv(DEVICE_ENV, raising=False)
    expected = "cuda" if torch.cuda.is_available() else "cpu"
    assert pick_device().type == pick_device("auto").type == expected


def test_the_environment_chooses_unless_the_caller_does(monkeypatch) -> None:
    monkeypatch.setenv(DEVICE_ENV, "cpu")
    assert pick_device() == torch.device("cpu")
    monkeypatch.setenv(DEVICE_ENV, "no-such-device")
    assert pick_device("cpu") == torch.device("cpu")
    with pytest.raises(ValueError, match="unknown device 'no-such-device'"):
        pick_device()


def test_a_device_the_machine_lacks_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="'cuda:64' asked for, but torch sees"):
        pick_device("cuda:64")
    with pytest.raises(ValueError, match="monitors run on cpu or cuda"):
        pick_device("meta")
