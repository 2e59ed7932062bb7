"""Adam as `torch.optim.Adam` computes it, without importing the compiler on first use.

Every `torch.optim.Optimizer` wraps its methods (`add_param_group`, `zero_grad`, `step`) to keep
`torch.compile` out, and the wrapper imports `torch._dynamo` on its first call: ≈ 1 s of CPU
once per process, for a campaign round's ≈ 120 optimiser steps that take ≈ 0.15 s. `Adam` keeps
the state `torch.optim.Adam` keeps (created on a parameter's first step with a gradient) and
steps through the very function `torch.optim.Adam.step` calls (`torch.optim.adam.adam`, its
functional API), so it gives the same parameters bit for bit
(tests/monitor/test_adam.py checks them against `torch.optim.Adam`).
"""

from __future__ import annotations

from collections.abc import Iterable

import torch
from torch.optim.adam import adam


class Adam:
    """Adam (L2 weight decay, no AMSGrad) over `params`, with `zero_grad()` and `step()`."""

    def __init__(self, params: Iterable[torch.nn.Parameter], lr: float = 1e-3,
                 weight_decay: float = 0.0, betas: tuple[float, float] = (0.9, 0.999),
                 eps: float = 1e-8) -> None:
        self.params = list(params)
        self.lr, self.weight_decay, self.betas, self.eps = lr, weight_decay, betas, eps
        # per parameter: (step count, first and second moment estimates), as torch keeps them
        self.state: dict[torch.Tensor, tuple[torch.Tensor, torch.Tensor, torch.Tensor]] = {}

    def zero_grad(self) -> None:
        """Drop every gradient (`set_to_none=True`)."""
        for p in self.params:
            p.grad = None

    @torch.no_grad()
    def step(self) -> None:
        """One update of every parameter that has a gradient."""
        live = [p for p in self.params if p.grad is not None]
        for p in live:
            if p not in self.state:
                self.state[p] = _initial_state(p)
        steps, exp_avgs, exp_avg_sqs = ([self.state[p][k] for p in live] for k in range(3))
        adam(live, [p.grad for p in live], exp_avgs, exp_avg_sqs, [], steps, foreach=None,
             amsgrad=False, beta1=self.betas[0], beta2=self.betas[1], lr=self.lr,
             weight_decay=self.weight_decay, eps=self.eps, maximize=False)


def _initial_state(p: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """(step, exp_avg, exp_avg_sq) of a parameter before its first step, as torch makes them."""
    step_dtype = torch.float64 if torch.get_default_dtype() == torch.float64 else torch.float32
    return (torch.tensor(0.0, dtype=step_dtype, device="cpu"),
            torch.zeros_like(p, memory_format=torch.preserve_format),
            torch.zeros_like(p, memory_format=torch.preserve_format))
