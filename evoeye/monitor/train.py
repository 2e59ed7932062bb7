"""Train FusionMonitors on SQL-selected warehouse windows and save each as a version with a card.

The windows are the eligible frames of the selected runs (`load_windows`): no frame at or after
a run's collision enters training, `pos_weight`, early stopping or calibration. How a network
learns from them — loss, batches, schedule, early stopping — is `evoeye.monitor.fit`, with the
hyper-parameters of a named recipe (`evoeye.monitor.recipes`: "v3" by default, "v1" the one
every earlier result was made with) and the caller's overrides; the card records both.

`init_from=<version>` fine-tunes a parent: its weights, input normalisers and architecture are
the starting point, and the card records the parent. Without it a monitor is trained from
scratch, with normalisers fitted on the training frames.

`train_monitors` trains several seeds of one recipe on the same data: the windows are loaded
once and the seeds train side by side, on the CPU each in a process forked after the loading
(`evoeye.monitor.side_by_side`), on a GPU each in a thread, each with the one intra-op thread a
seed trained alone has. A seed's computation is then the very sequence of kernels it runs alone,
so its weights, and its version, are those `train_monitor` gives for that seed, bit for bit
(tests/monitor/test_train_seeds.py). The seeds run on the device `evoeye.monitor.device` picks:
a GPU when there is one.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from typing import Any

import numpy as np
import torch

from evoeye import __version__
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.card import (
    data_summary,
    describe_selection,
    split_metrics,
    thresholds_to_card,
)
from evoeye.monitor.device import pick_device
from evoeye.monitor.fit import FitResult, Progress, fit, kernels, reproducible
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.lookahead import PAUC_MAX_FPR, critical_target, critical_times
from evoeye.monitor.model import MODULES, FusionConfig, FusionNet
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.recipes import (
    RECIPE_NETWORKS,
    TrainParams,
    card_hyperparameters,
    recipe_params,
)
from evoeye.monitor.registry import load_monitor, save_version
from evoeye.monitor.side_by_side import can_fork, map_forked
from evoeye.paths import DataRoot
from evoeye.store.catalog import Warehouse
from evoeye.store.features import FrameFeatures
from evoeye.store.selection import RunFilter, Runs, SplitSpec
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S, Windows, load_windows

# the card's record of the early-stopping criterion (TrainParams.select_on)
EARLY_STOPPING = {"auprc": "val AUPRC", "pauc": f"val pAUC (FPR <= {PAUC_MAX_FPR:g})"}
_reproducible = reproducible  # the name tests and older callers import
__all__ = ["FitResult", "TrainParams", "Trained", "fit", "fit_windows", "train_monitor",
           "train_monitors"]


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
    kinematics: bool | None = None,
    seed: int = 0,
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    train_runs: Runs = None,
    val_runs: Runs = None,
    init_from: str | None = None,
    params: TrainParams | None = None,
    progress: Progress | None = None,
    recipe: str | None = None,
    device: str | torch.device | None = None,
    run_weights: Mapping[str, float] | None = None,
    **overrides: Any,
) -> str:
    """Train (or fine-tune, with `init_from`) a FusionMonitor and save it; its version id.

    Default data: the `scenario` runs of the train / val splits of `splits`; `train_runs` /
    `val_runs` (a RunFilter, SQL returning scenario_id, or ids) select any other subsets.
    `context_len` (default 5), `modules` (default all four), `dropout` and `kinematics`
    (default FusionConfig's) come from the parent when fine-tuning. The hyper-parameters are
    those of `recipe` (default `recipes.DEFAULT_RECIPE`) with `overrides` (TrainParams fields:
    epochs=…, lr=…); a full `params` replaces all three and `seed`. `device`: `pick_device`'s.
    `run_weights`: scenario id → p/q of training runs, with `importance_weights=True`
    (`evoeye.monitor.importance`).
    """
    seed = params.seed if params is not None else seed
    return train_monitors(root, scenario, seeds=[seed], context_len=context_len,
                          horizon_s=horizon_s, modules=modules, dropout=dropout,
                          kinematics=kinematics, splits=splits,
                          train_runs=train_runs, val_runs=val_runs, init_from=init_from,
                          params=params, progress=progress, recipe=recipe, device=device,
                          run_weights=run_weights, **overrides)[0]


def train_monitors(
    root: DataRoot,
    scenario: str | None = None,
    *,
    seeds: Sequence[int],
    context_len: int | None = None,
    horizon_s: float = DEFAULT_HORIZON_S,
    modules: Sequence[str] | None = None,
    dropout: float | None = None,
    kinematics: bool | None = None,
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    train_runs: Runs = None,
    val_runs: Runs = None,
    init_from: str | None = None,
    params: TrainParams | None = None,
    progress: Progress | None = None,
    recipe: str | None = None,
    device: str | torch.device | None = None,
    parallel: int | None = None,
    run_weights: Mapping[str, float] | None = None,
    **overrides: Any,
) -> list[str]:
    """`train_monitor` once per seed, on data loaded once; the version ids, in `seeds`' order,
    each the one `train_monitor` gives for that seed (module doc). `parallel` seeds train at a
    time (default: all; time-shared, k seeds on n cores take ≈ k / n of one seed's time);
    `progress` rows carry their "seed". A network with dropout draws from the global RNG while
    it trains, so in threads (a GPU, or a platform without fork) its seeds train one after the
    other."""
    if not seeds or len(set(seeds)) != len(seeds):
        raise ValueError(f"give distinct training seeds, got {list(seeds)}")
    base = params or recipe_params(recipe, **overrides)
    train_runs, val_runs = _selections(scenario, splits, train_runs, val_runs)
    parent = load_monitor(root, init_from) if init_from else None
    if parent is None:  # the recipe's network, where the caller says nothing else
        preset = RECIPE_NETWORKS.get(base.recipe, {})
        context_len = context_len if context_len is not None else preset.get("context_len")
        kinematics = kinematics if kinematics is not None else preset.get("kinematics")
    config = _config(parent, context_len, modules, dropout, kinematics)
    warehouse = Warehouse(root)
    train = load_windows(warehouse, train_runs, context_len=config.context_len,
                         horizon_s=horizon_s)
    val = load_windows(warehouse, val_runs, context_len=config.context_len, horizon_s=horizon_s)
    if base.target == "critical":  # trained and selected on critical approaches too
        critical = critical_times(root, np.concatenate([train.scenario_id, val.scenario_id]))
        train, val = critical_target(train, critical), critical_target(val, critical)
    where = pick_device(device)
    norms = None if parent is not None else _fitted_normalizers(train, config)

    def start(seed: int) -> FusionNet:
        if parent is not None:
            return copy.deepcopy(parent.net).to(where)
        net = FusionNet(FusionConfig.for_spec(train.spec, **_sizes(config)))
        net.norm.load_state_dict(norms)  # the same for every seed: fitted once
        return net.to(where)

    def run(seed: int, net: FusionNet | None = None, report: Progress | None = None) -> Trained:
        p = replace(base, seed=seed)
        with reproducible(seed, p.threads, where.type == "cpu") if net is None else kernels(
                p.threads, where.type == "cpu"):
            net = net or start(seed)
            result = fit(net, train, val, p, report, run_weights)
            scores = FusionMonitor(result.net, "training", None,  # type: ignore[arg-type]
                                   device=where).score(val)
        return Trained(p, result, scores, calibrate_on_validation(scores, val))

    width = min(len(seeds), parallel or len(seeds))
    if width > 1 and where.type == "cpu" and can_fork():
        # each seed in a process forked from this one: initialised there under its seed, as alone
        trained = map_forked(lambda seed, send: run(seed, report=send), seeds, width=width,
                             on_message=None if progress is None else (
                                 lambda seed, row: progress({**row, "seed": seed})))
    elif width == 1 or config.dropout > 0:
        trained = [run(seed, report=_tagged(progress, seed)) for seed in seeds]
    else:
        nets = []
        for seed in seeds:  # each initialised under its seed, as alone
            with reproducible(seed, base.threads):
                nets.append(start(seed))
        # the kernels' global settings held around the threads: each thread's own `kernels`
        # then saves and restores the same values, so no interleaving leaves them changed
        with kernels(base.threads, where.type == "cpu"), ThreadPoolExecutor(width) as pool:
            trained = list(pool.map(lambda seed, net: run(seed, net, _tagged(progress, seed)),
                                    seeds, nets))
    return [init_from if init_from and t.result.best_epoch == 0 else  # no epoch beat the parent
            save_version(root, t.result.net.cpu(),
                         _card(t, scenario, horizon_s, init_from, config, train, val,
                               train_runs, val_runs, where))
            for t in trained]


@dataclass
class Trained:
    """A fit, its parameters, its validation scores and the thresholds calibrated on them."""

    params: TrainParams
    result: FitResult
    scores: np.ndarray  # (B,) of the validation windows
    thresholds: Thresholds


def _tagged(progress: Progress | None, seed: int) -> Progress | None:
    """`progress` called with each row and its seed."""
    return None if progress is None else (lambda row: progress({**row, "seed": seed}))


def _config(parent: FusionMonitor | None, context_len: int | None,
            modules: Sequence[str] | None, dropout: float | None,
            kinematics: bool | None = None) -> FusionConfig:
    """The network's config: the parent's (which the options must not contradict), or one
    made of the options."""
    if parent is not None:
        config = parent.net.config
        if context_len not in (None, config.context_len) or dropout not in (
                None, config.dropout) or (modules is not None and tuple(modules) != config.modules
                                          ) or kinematics not in (None, config.kinematics):
            raise ValueError(f"a fine-tuned monitor keeps its parent's L = {config.context_len}, "
                             f"modules {config.modules}, dropout {config.dropout} and "
                             f"kinematics {config.kinematics}")
        return config
    extra = {} if dropout is None else {"dropout": dropout}
    if kinematics is not None:
        extra["kinematics"] = kinematics
    return FusionConfig(context_len=context_len or DEFAULT_CONTEXT_LEN,
                        modules=tuple(modules or MODULES), **extra)


def _card(t: Trained, scenario: str | None, horizon_s: float, init_from: str | None,
          config: FusionConfig, train: Windows, val: Windows, train_runs: Runs,
          val_runs: Runs, device: torch.device) -> dict[str, Any]:
    result = t.result
    return {
        "name": FusionMonitor.name,
        "created_at": datetime.now(UTC).isoformat(timespec="seconds"),
        "software_version": __version__,
        "parent": init_from,
        "logical_scenario": scenario,
        "horizon_s": float(horizon_s),
        "context_len": config.context_len,
        "modules": list(config.modules),
        "n_parameters": result.net.n_parameters(),
        "recipe": t.params.recipe,
        "selection": {"train": describe_selection(train_runs),
                      "val": describe_selection(val_runs)},
        "data": {"train": data_summary(train), "val": data_summary(val)},
        "config": result.net.config.to_dict(),
        "hyperparameters": {**card_hyperparameters(t.params), "pos_weight": result.pos_weight,
                            "loss": "BCEWithLogitsLoss(pos_weight)", "optimizer": "Adam",
                            "early_stopping": EARLY_STOPPING[t.params.select_on]},
        "training": {"best_epoch": result.best_epoch, "epochs_run": len(result.history),
                     "time_s": round(result.time_s, 2), "cpu_s": round(result.cpu_s, 2),
                     "device": str(device), "phases": result.phases,
                     "history": result.history},
        **({} if result.importance is None else {"importance": result.importance}),
        **thresholds_to_card(t.thresholds),
        "metrics": {"val": split_metrics(t.scores, val.label, t.thresholds)},
    }


def fit_windows(train: Windows, val: Windows, params: TrainParams | None = None, *,
                config: FusionConfig | None = None, parent: FusionNet | None = None,
                progress: Progress | None = None,
                device: str | torch.device | None = None,
                run_weights: Mapping[str, float] | None = None) -> Trained:
    """Train a new FusionNet of `config` (default sizes; normalisers fitted on the training
    frames), or fine-tune a copy of `parent`, on windows in memory, with `params` (default: the
    default recipe's), and calibrate it on `val`. Seeded by `params.seed`; nothing is saved
    (`train_monitor` saves). `run_weights` as `fit`'s."""
    params = params or recipe_params()
    where = pick_device(device)
    with reproducible(params.seed, params.threads, where.type == "cpu"):
        if parent is not None:
            net = copy.deepcopy(parent)
        else:
            net = FusionNet(FusionConfig.for_spec(train.spec,
                                                  **_sizes(config or FusionConfig())))
            net.fit_normalizers(_frames_of(train))
        result = fit(net.to(where), train, val, params, progress, run_weights)
        scores = FusionMonitor(result.net, "training", None,  # type: ignore[arg-type]
                               device=where).score(val)
    return Trained(params, result, scores, calibrate_on_validation(scores, val))


def _sizes(config: FusionConfig) -> dict[str, Any]:
    """The config's fields other than the input sizes (those come from the FeatureSpec)."""
    d = config.to_dict()
    for key in ("max_obstacles", "pred_points", "plan_points"):
        d.pop(key)
    d["modules"] = tuple(d["modules"])
    return d


def _fitted_normalizers(train: Windows, config: FusionConfig) -> dict[str, torch.Tensor]:
    """The input normalisers' state of a network of `config` fitted on the training frames:
    seed-independent, so fitted once for every seed (a network made aside, the caller's random
    generator left as it was)."""
    with torch.random.fork_rng(devices=[]):
        net = FusionNet(FusionConfig.for_spec(train.spec, **_sizes(config)))
    net.fit_normalizers(_frames_of(train))
    return net.norm.state_dict()


def _frames_of(windows: Windows) -> FrameFeatures:
    """The feature rows of the frames the windows end at (each frame once)."""
    rows = np.unique(windows.context[:, -1])
    return FrameFeatures(**{k: v[rows] for k, v in windows.features.arrays().items()})
