"""Train a FusionMonitor on SQL-selected warehouse windows and save it as a version with a card.

The windows are the eligible frames of the selected runs (`load_windows`): no frame at or after
a run's collision enters training, `pos_weight`, early stopping or calibration.

Loss: binary cross-entropy on the logit (`BCEWithLogitsLoss`) with `pos_weight` = negatives /
positives of the training windows. Unsafe frames are rare (≈ 4 % in S1, ≈ 16 % in S2), so
unweighted BCE is dominated by the easy safe frames; weighting the positives balances the two
classes in expectation while every window is still seen exactly once per epoch (unlike
re-sampling, which repeats a few positive windows and drops negatives). The weighting shifts the
scores upwards, which does not matter for alarms: thresholds are calibrated on validation for a
target FPR. Optimiser Adam (`evoeye.monitor.adam`: torch's, without its compiler import); early
stopping on validation AUPRC (the best epoch's weights are kept). Seeded: the same seed, data
and thread count give the same weights (and version).

`init_from=<version>` fine-tunes a parent: its weights, input normalisers and architecture are
the starting point, and the card records the parent. Without it a monitor is trained from
scratch, with normalisers fitted on the training frames.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from typing import Any

import numpy as np
import torch
from torch import nn

from evoeye import __version__
from evoeye.monitor.adam import Adam
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.card import (
    data_summary,
    describe_selection,
    ranking_metrics,
    split_metrics,
    thresholds_to_card,
)
from evoeye.monitor.fusion import FusionMonitor, net_inputs
from evoeye.monitor.model import MODULES, FusionConfig, FusionNet
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.registry import load_monitor, save_version
from evoeye.monitor.threads import MONITOR_THREADS, intra_op_threads
from evoeye.paths import DataRoot
from evoeye.store.catalog import Warehouse
from evoeye.store.features import FrameFeatures
from evoeye.store.selection import RunFilter, Runs, SplitSpec
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S, Windows, load_windows

Progress = Callable[[dict[str, Any]], None]  # called after every epoch with its history row


@dataclass(frozen=True)
class TrainParams:
    """Hyper-parameters of one training run (recorded in the card)."""

    seed: int = 0
    epochs: int = 40  # at most; early stopping usually ends sooner
    patience: int = 8  # epochs without a better validation AUPRC before stopping
    batch_size: int = 256
    lr: float = 1e-3
    weight_decay: float = 1e-5
    grad_clip: float = 1.0
    pos_weight: float | None = None  # None: negatives / positives of the training windows
    threads: int = MONITOR_THREADS  # intra-op threads (evoeye.monitor.threads says why one)


@dataclass
class FitResult:
    """The trained network (best validation epoch) and how training went."""

    net: FusionNet
    best_epoch: int
    history: list[dict[str, Any]]
    pos_weight: float
    time_s: float


def _deterministic(mode: bool) -> None:
    """torch.use_deterministic_algorithms without its import of torch._inductor (≈ 1.4 s once
    per process, to set a compiler flag for torch.compile, which evoeye never uses)."""
    setter = getattr(torch._C, "_set_deterministic_algorithms", None)
    if setter is None:  # another torch: the public call
        torch.use_deterministic_algorithms(mode)
    else:
        setter(mode)


@contextmanager
def _reproducible(seed: int, threads: int):
    """Seeded global RNG, deterministic kernels and a fixed thread count; all restored after."""
    was_deterministic = torch.are_deterministic_algorithms_enabled()
    with torch.random.fork_rng(devices=[]), intra_op_threads(threads):
        torch.manual_seed(seed)
        _deterministic(True)
        try:
            yield
        finally:
            _deterministic(was_deterministic)


def _val_score(net: FusionNet, val: Windows) -> tuple[np.ndarray, float]:
    """(val risks, val BCE) of the network in eval mode."""
    scores = FusionMonitor(net, "training", None, trace=False).score(val)  # type: ignore
    net.train()
    p = np.clip(scores.astype(np.float64), 1e-7, 1 - 1e-7)
    y = val.label.astype(np.float64)
    return scores, float(-(y * np.log(p) + (1 - y) * np.log(1 - p)).mean())


def fit(net: FusionNet, train: Windows, val: Windows, params: TrainParams = TrainParams(),
        progress: Progress | None = None) -> FitResult:
    """Train `net` in place on `train`, early-stopped on `val` AUPRC; the best epoch's net.

    Call under `_reproducible` (train_monitor does) for seeded, repeatable weights.
    """
    if len(train) == 0 or len(val) == 0:
        raise ValueError(f"need training and validation windows, got {len(train)} and "
                         f"{len(val)}: check the run selection")
    n_pos = int(train.label.sum())
    if n_pos == 0 or n_pos == len(train):
        raise ValueError(f"the training windows need both classes; {n_pos} of {len(train)} "
                         "are unsafe")
    pos_weight = params.pos_weight or (len(train) - n_pos) / n_pos
    loss_fn = nn.BCEWithLogitsLoss(pos_weight=torch.tensor(pos_weight))
    opt = Adam(net.parameters(), lr=params.lr, weight_decay=params.weight_decay)
    gen = torch.Generator().manual_seed(params.seed)
    # AUPRC needs both classes in validation; without, early stopping falls back to val loss
    use_auprc = ranking_metrics(np.zeros(len(val)), val.label)["auprc"] is not None
    best, best_state, best_epoch, history = -np.inf, copy.deepcopy(net.state_dict()), 0, []
    t0 = time.perf_counter()
    net.train()
    for epoch in range(1, params.epochs + 1):
        order = torch.randperm(len(train), generator=gen).numpy()
        total = 0.0
        for start in range(0, len(order), params.batch_size):
            idx = np.sort(order[start:start + params.batch_size])  # sorted: faster gather
            batch = train.batch(idx)
            logit = net(*net_inputs(batch))
            loss = loss_fn(logit, batch.label)
            opt.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(net.parameters(), params.grad_clip)
            opt.step()
            total += float(loss.detach()) * len(idx)
        scores, val_loss = _val_score(net, val)
        metrics = ranking_metrics(scores, val.label)
        row = {"epoch": epoch, "train_loss": total / len(train), "val_loss": val_loss, **metrics}
        history.append(row)
        criterion = metrics["auprc"] if use_auprc else -val_loss
        if criterion > best + 1e-6:
            best, best_epoch, best_state = criterion, epoch, copy.deepcopy(net.state_dict())
        if progress is not None:
            progress(row)
        if epoch - best_epoch >= params.patience:
            break
    net.load_state_dict(best_state)
    net.eval()
    return FitResult(net, best_epoch, history, pos_weight, time.perf_counter() - t0)


def _selections(scenario: str | None, splits: SplitSpec, train_runs: Runs, val_runs: Runs
                ) -> tuple[Runs, Runs]:
    if train_runs is None or val_runs is None:
        if scenario is None:
            raise ValueError("give a logical scenario, or both train_runs and val_runs")
        train_runs = train_runs or RunFilter(logical_scenario=scenario, split="train",
                                             splits=splits)
        val_runs = val_runs or RunFilter(logical_scenario=scenario, split="val", splits=splits)
    return train_runs, val_runs


def train_monitor(
    root: DataRoot,
    scenario: str | None = None,
    *,
    context_len: int | None = None,
    horizon_s: float = DEFAULT_HORIZON_S,
    modules: Sequence[str] | None = None,
    dropout: float | None = None,
    seed: int = 0,
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    train_runs: Runs = None,
    val_runs: Runs = None,
    init_from: str | None = None,
    params: TrainParams | None = None,
    progress: Progress | None = None,
    **overrides: Any,
) -> str:
    """Train (or fine-tune, with `init_from`) a FusionMonitor and save it; its version id.

    Default data: the `scenario` runs of the train / val splits of `splits`; `train_runs` /
    `val_runs` (a RunFilter, SQL returning scenario_id, or ids) select any other subsets.
    `context_len` (default 5), `modules` (default all four) and `dropout` (default
    FusionConfig's) come from the parent when fine-tuning. `overrides` set TrainParams fields
    (epochs=…, lr=…); a full `params` replaces both them and `seed`.
    """
    params = params or TrainParams(seed=seed, **overrides)
    train_runs, val_runs = _selections(scenario, splits, train_runs, val_runs)
    parent = load_monitor(root, init_from) if init_from else None
    if parent is not None:
        config = parent.net.config
        if context_len not in (None, config.context_len) or dropout not in (
                None, config.dropout) or (modules is not None and tuple(modules) != config.modules):
            raise ValueError(f"a fine-tuned monitor keeps its parent's L = {config.context_len}, "
                             f"modules {config.modules} and dropout {config.dropout}")
    else:
        extra = {} if dropout is None else {"dropout": dropout}
        config = FusionConfig(context_len=context_len or DEFAULT_CONTEXT_LEN,
                              modules=tuple(modules or MODULES), **extra)
    warehouse = Warehouse(root)
    train = load_windows(warehouse, train_runs, context_len=config.context_len,
                         horizon_s=horizon_s)
    val = load_windows(warehouse, val_runs, context_len=config.context_len, horizon_s=horizon_s)
    trained = fit_windows(train, val, params, config=config,
                          parent=None if parent is None else parent.net, progress=progress)
    result, thresholds, scores = trained.result, trained.thresholds, trained.val_scores
    card = {
        "name": FusionMonitor.name,
        "created_at": datetime.now(UTC).isoformat(timespec="seconds"),
        "software_version": __version__,
        "parent": init_from,
        "logical_scenario": scenario,
        "horizon_s": float(horizon_s),
        "context_len": config.context_len,
        "modules": list(config.modules),
        "n_parameters": result.net.n_parameters(),
        "selection": {"train": describe_selection(train_runs),
                      "val": describe_selection(val_runs)},
        "data": {"train": data_summary(train), "val": data_summary(val)},
        "config": result.net.config.to_dict(),
        "hyperparameters": {**asdict(params), "pos_weight": result.pos_weight,
                            "loss": "BCEWithLogitsLoss(pos_weight)", "optimizer": "Adam",
                            "early_stopping": "val AUPRC"},
        "training": {"best_epoch": result.best_epoch, "epochs_run": len(result.history),
                     "time_s": round(result.time_s, 2), "history": result.history},
        **thresholds_to_card(thresholds),
        "metrics": {"val": split_metrics(scores, val.label, thresholds)},
    }
    return save_version(root, result.net, card)


@dataclass
class Trained:
    """A fit, its thresholds calibrated on validation, and its validation scores."""

    result: FitResult
    thresholds: Thresholds
    val_scores: np.ndarray  # (B_val,) float32


def fit_windows(train: Windows, val: Windows, params: TrainParams = TrainParams(), *,
                config: FusionConfig | None = None, parent: FusionNet | None = None,
                progress: Progress | None = None) -> Trained:
    """Train a new FusionNet of `config` (default sizes; normalisers fitted on the training
    frames), or fine-tune a copy of `parent`, on windows in memory: early-stopped on `val`,
    calibrated on it. Seeded by `params.seed`; nothing is saved (`train_monitor` saves)."""
    with _reproducible(params.seed, params.threads):
        if parent is not None:
            net = copy.deepcopy(parent)
        else:
            net = FusionNet(FusionConfig.for_spec(train.spec,
                                                  **_sizes(config or FusionConfig())))
            net.fit_normalizers(_frames_of(train))
        result = fit(net, train, val, params, progress)
    with intra_op_threads(params.threads):
        scores = FusionMonitor(result.net, "training", None).score(val)  # type: ignore[arg-type]
    return Trained(result, calibrate_on_validation(scores, val), scores)


def _sizes(config: FusionConfig) -> dict[str, Any]:
    """The config's fields other than the input sizes (those come from the FeatureSpec)."""
    d = config.to_dict()
    for key in ("max_obstacles", "pred_points", "plan_points"):
        d.pop(key)
    d["modules"] = tuple(d["modules"])
    return d


def _frames_of(windows: Windows) -> FrameFeatures:
    """The feature rows of the frames the windows end at (each frame once)."""
    rows = np.unique(windows.context[:, -1])
    return FrameFeatures(**{k: v[rows] for k, v in windows.features.arrays().items()})
