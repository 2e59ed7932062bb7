"""The training loop of a FusionMonitor: epochs of batches, validation, early stopping.

Loss: binary cross-entropy on the logit (`BCEWithLogitsLoss`) with `pos_weight` = negatives /
positives of the training windows. Unsafe frames are rare (≈ 4 % in S1, ≈ 16 % in S2), so
unweighted BCE is dominated by the easy safe frames; weighting the positives balances the two
classes in expectation while every window is still seen exactly once per epoch (unlike
re-sampling, which repeats a few positive windows and drops negatives). The weighting shifts the
scores upwards, which does not matter for alarms: thresholds are calibrated on validation for a
target FPR. Optimiser Adam (`evoeye.monitor.adam`: torch's, without its compiler import), its
learning rate per step from the recipe's schedule; batches as the recipe's batching makes them
(`evoeye.monitor.batching`); early stopping on validation AUPRC after every epoch (the best
epoch's weights are kept; a recipe may select on the partial AUROC of the strict-threshold end
instead, and leave the last moments before contact out of training: `evoeye.monitor.lookahead`).
Seeded: the same seed, data and thread count give the same weights.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import nn

from evoeye.monitor.adam import Adam
from evoeye.monitor.batching import BATCHINGS, lr_schedule
from evoeye.monitor.card import ranking_metrics
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.importance import window_weights
from evoeye.monitor.lookahead import selection_metric, training_windows
from evoeye.monitor.model import FusionNet
from evoeye.monitor.recipes import TrainParams
from evoeye.monitor.threads import intra_op_threads
from evoeye.phases import PhaseClock
from evoeye.store.windows import Windows

Progress = Callable[[dict[str, Any]], None]  # called after every epoch with its history row
# where a training's time goes: making and gathering batches, the forward pass and loss, the
# backward pass, clipping and the optimiser step, validation after every epoch
FIT_PHASES = ("batches", "forward", "backward", "optimiser", "validation")


@dataclass
class FitResult:
    """The trained network (best validation epoch) and how training went."""

    net: FusionNet
    best_epoch: int
    history: list[dict[str, Any]]
    pos_weight: float
    time_s: float  # wall seconds of the loop
    cpu_s: float  # CPU seconds of the thread that ran it (load inflates wall time, not this)
    phases: dict[str, dict[str, float]]  # FIT_PHASES: {"wall_s", "cpu_s"} of each
    importance: dict | None = None  # the weights' summary with `importance_weights` (card)


def _deterministic(mode: bool) -> None:
    """torch.use_deterministic_algorithms without its import of torch._inductor (≈ 1.4 s once
    per process, to set a compiler flag for torch.compile, which evoeye never uses)."""
    setter = getattr(torch._C, "_set_deterministic_algorithms", None)
    if setter is None:  # another torch: the public call
        torch.use_deterministic_algorithms(mode)
    else:
        setter(mode)


@contextmanager
def kernels(threads: int, deterministic: bool = True) -> Iterator[None]:
    """Deterministic kernels (if asked) and a fixed intra-op thread count; restored after."""
    was_deterministic = torch.are_deterministic_algorithms_enabled()
    with intra_op_threads(threads):
        _deterministic(deterministic)
        try:
            yield
        finally:
            _deterministic(was_deterministic)


@contextmanager
def reproducible(seed: int, threads: int, deterministic: bool = True) -> Iterator[None]:
    """`kernels` and a seeded global RNG (forked: the caller's is restored after)."""
    with torch.random.fork_rng(devices=[]), kernels(threads, deterministic):
        torch.manual_seed(seed)
        yield


def _val_score(net: FusionNet, val: Windows) -> tuple[np.ndarray, float]:
    """(val risks, val BCE) of the network in eval mode."""
    device = next(net.parameters()).device
    scores = FusionMonitor(net, "training", None, trace=False,  # type: ignore[arg-type]
                           device=device).score(val)
    net.train()
    p = np.clip(scores.astype(np.float64), 1e-7, 1 - 1e-7)
    y = val.label.astype(np.float64)
    return scores, float(-(y * np.log(p) + (1 - y) * np.log(1 - p)).mean())


def check_windows(train: Windows, val: Windows) -> int:
    """The unsafe windows of `train`; ValueError if either set cannot train a monitor."""
    if len(train) == 0 or len(val) == 0:
        raise ValueError(f"need training and validation windows, got {len(train)} and "
                         f"{len(val)}: check the run selection")
    n_pos = int(train.label.sum())
    if n_pos == 0 or n_pos == len(train):
        raise ValueError(f"the training windows need both classes; {n_pos} of {len(train)} "
                         "are unsafe")
    return n_pos


def fit(net: FusionNet, train: Windows, val: Windows,
        params: TrainParams = TrainParams(),  # noqa: B008 (frozen dataclass)
        progress: Progress | None = None,
        run_weights: Mapping[str, float] | None = None) -> FitResult:
    """Train `net` in place on `train`, on the device it sits on, early-stopped on `val`
    AUPRC; the best epoch's net. With `params.keep_parent` the weights it starts from are
    epoch 0, kept (best_epoch 0) unless an epoch beats them: a fine-tune that only loses keeps
    its parent. With `params.importance_weights` each window's loss is weighted by its run's
    p/q from `run_weights` (scenario id → p/q; a run missing: 1), as `evoeye.monitor.importance`
    says; ValueError for `run_weights` without that option.

    Call under `reproducible` (train_monitor does) for seeded, repeatable weights; without
    dropout the loop draws no number from the global RNG, so `kernels` is enough.
    """
    train = training_windows(train, params.min_lead_s, params.near_misses)
    n_pos = check_windows(train, val)
    device = next(net.parameters()).device
    weights, importance = None, None
    if params.importance_weights:
        w, importance = window_weights(train.scenario_id, run_weights)
        weights = torch.from_numpy(w).to(device)
        unsafe = train.label.astype(bool)
        pos_weight = params.pos_weight or float(w[~unsafe].sum() / w[unsafe].sum())
    elif run_weights is not None:
        raise ValueError("run weights given, but the training's importance_weights is off")
    else:
        pos_weight = params.pos_weight or (len(train) - n_pos) / n_pos
    loss_fn = nn.BCEWithLogitsLoss(pos_weight=torch.tensor(pos_weight, device=device),
                                   reduction="mean" if weights is None else "none")
    opt = Adam(net.parameters(), lr=params.lr, weight_decay=params.weight_decay)
    gen = torch.Generator().manual_seed(params.seed)
    batches = BATCHINGS[params.batching](train, params, device)
    lr_at = lr_schedule(params, batches.steps())
    # AUPRC (pAUC) needs both classes in validation; without, early stopping uses the val loss
    use_auprc = ranking_metrics(np.zeros(len(val)), val.label)["auprc"] is not None
    select = params.select_on
    best, best_state, best_epoch, history = -np.inf, copy.deepcopy(net.state_dict()), 0, []
    clock = PhaseClock(FIT_PHASES, time.thread_time)
    t0, c0 = time.perf_counter(), time.thread_time()

    def validate() -> tuple[dict[str, Any], float, float]:  # metrics, loss, stopping criterion
        scores, val_loss = _val_score(net, val)
        metrics = ranking_metrics(scores, val.label)
        if select != "auprc" and use_auprc:  # another criterion: recorded beside AUROC, AUPRC
            metrics[select] = selection_metric(select, scores, val.label)
        return metrics, val_loss, metrics[select] if use_auprc else -val_loss

    if params.keep_parent:  # the starting weights are epoch 0
        with clock("validation"):
            best = validate()[2]
    step = 0
    net.train()
    for epoch in range(1, params.epochs + 1):
        total = 0.0
        with clock("batches"):
            epoch_batches = batches.epoch(gen)
        for idx in epoch_batches:
            with clock("batches"):
                batch = batches.gather(idx)
            with clock("forward"):
                loss = loss_fn(batches.forward(net, batch), batch.label)
                if weights is not None:  # (b,) losses, each times its window's weight
                    loss = (loss * weights[torch.from_numpy(idx).to(device)]).mean()
            with clock("backward"):
                opt.zero_grad()
                loss.backward()
            with clock("optimiser"):
                opt.lr = lr_at(step)
                step += 1
                nn.utils.clip_grad_norm_(net.parameters(), params.grad_clip)
                opt.step()
                total += float(loss.detach()) * len(idx)
        with clock("validation"):
            metrics, val_loss, criterion = validate()
            row = {"epoch": epoch, "train_loss": total / len(train), "val_loss": val_loss,
                   **metrics}
            history.append(row)
            if criterion > best + 1e-6:
                best, best_epoch, best_state = criterion, epoch, copy.deepcopy(net.state_dict())
        if progress is not None:
            progress(row)
        if epoch - best_epoch >= params.patience:
            break
    net.load_state_dict(best_state)
    net.eval()
    return FitResult(net, best_epoch, history, pos_weight, time.perf_counter() - t0,
                     time.thread_time() - c0, clock.rounded(), importance)
