"""Where monitors train and score: a CUDA GPU when there is one, else the CPU.

The CPU is the reference: with one intra-op thread and deterministic kernels it gives the same
weights and scores bit for bit on every run (the tests run there). A GPU gives the same
training up to floating-point rounding — other kernels sum in another order — so its weights,
and the versions named by them, differ from the CPU's; `EVOEYE_DEVICE=cpu` (or device="cpu")
keeps a GPU machine on the reference path, e.g. to reproduce recorded figures byte for byte.
"""

from __future__ import annotations

import os

import torch

DEVICE_ENV = "EVOEYE_DEVICE"


def pick_device(name: str | torch.device | None = None) -> torch.device:
    """`name` ("cpu", "cuda", "cuda:1"), else $EVOEYE_DEVICE, else CUDA if torch sees a GPU,
    else the CPU; ValueError naming a device this machine does not have."""
    name = name if name is not None else os.environ.get(DEVICE_ENV) or None
    if name is None or name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        device = torch.device(name)
    except RuntimeError as exc:
        raise ValueError(f"unknown device {str(name)!r} ({exc}); give cpu, cuda or cuda:N") \
            from None
    if device.type == "cuda" and not (torch.cuda.is_available() and (
            device.index is None or device.index < torch.cuda.device_count())):
        raise ValueError(f"device {str(name)!r} asked for, but torch sees "
                         f"{torch.cuda.device_count()} CUDA device(s)")
    if device.type not in ("cpu", "cuda"):
        raise ValueError(f"device {str(name)!r}: monitors run on cpu or cuda")
    return device
