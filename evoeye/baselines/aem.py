"""AEM baseline (AutoEncode-Monitor): reconstruction error of the module inputs as the risk.

Inspired by SelfOracle, but over the FusionMonitor's inputs: every window's perception,
prediction, planning and control arrays with their masks (padded context slots zeroed),
flattened to one vector, standardised with the training mean and std, and passed through an
MLP autoencoder. It is trained on collision-free frames only: windows labelled 0 whose frame is
before the run's collision (or in a run without one) — the caller passes that selection. The
score is e / (e + ẽ), e the window's mean squared reconstruction error and ẽ the median error on
the training windows: monotone in e, 0.5 at a typical normal window, → 1 for outliers.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from evoeye.monitor.adam import Adam
from evoeye.monitor.batching import step_lrs
from evoeye.monitor.card import thresholds_from_card
from evoeye.monitor.families import read_version
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.threads import intra_op_threads
from evoeye.store.windows import Windows

INPUT_ARRAYS = (  # (array, mask or None): the FusionMonitor's module inputs
    ("perception", "perception_mask"),
    ("prediction", "prediction_mask"),
    ("plan", "plan_mask"),
    ("plan_info", None),
    ("control", None),
)
CHUNK = 8192  # windows gathered at a time (a window is ~L·350 floats)
MODEL_FILE, META_FILE = "model.pt", "meta.json"


@dataclass(frozen=True)
class AEMConfig:
    """Autoencoder shape and training schedule; the defaults are recipe "v1"."""

    context_len: int = 5
    hidden: tuple[int, ...] = (256, 64)
    latent: int = 16
    epochs: int = 25
    batch_size: int = 256
    lr: float = 1e-3  # the peak learning rate under a schedule
    weight_decay: float = 1e-5
    max_train_windows: int = 200_000
    seed: int = 0
    # -- fields added with the recipes; `record` leaves them out where they are v1's
    recipe: str = "v1"
    schedule: str = "constant"  # evoeye.monitor.batching.SCHEDULES, over `epochs`' steps
    warmup_epochs: float = 0.0

    def record(self) -> dict[str, Any]:
        """The config as versions, metadata and training keys record it: every field, but those
        added with the recipes only where they differ from v1's (v1 keeps its ids)."""
        return {k: v for k, v in asdict(self).items()
                if k not in ADDED_FIELDS or v != getattr(AEM_RECIPES["v1"], k)}


ADDED_FIELDS = ("recipe", "schedule", "warmup_epochs")
# the FusionMonitor's recipe names (evoeye.monitor.recipes), the AEM's part of each: v2 trains
# in batches of 1024 at a peak 3e-3 with a warm-up and a cosine decay over 8 epochs; v3 in
# batches of 32 at v1's constant 1e-3 for 3 epochs: v1's optimiser steps (its ranking follows
# the steps, not the epochs: docs/training.md) for 28 % of its CPU time
AEM_RECIPES = {
    "v1": AEMConfig(),
    "v2": AEMConfig(recipe="v2", epochs=8, batch_size=1024, lr=3e-3, schedule="cosine",
                    warmup_epochs=0.5),
    "v3": AEMConfig(recipe="v3", epochs=3, batch_size=32),
}
# the lookahead recipes change the FusionMonitor's target and network only: v3's AEM, the same
# weights and ledger units
AEM_RECIPES |= {name: AEM_RECIPES["v3"] for name in ("lookahead-v1",)}


def aem_config(recipe: str | None = None, **overrides: Any) -> AEMConfig:
    """The AEM part of a training recipe (default: the FusionMonitor's default recipe) with
    `overrides` (AEMConfig fields); ValueError naming an unknown recipe."""
    from evoeye.monitor.recipes import DEFAULT_RECIPE

    name = recipe or DEFAULT_RECIPE
    if name not in AEM_RECIPES:
        raise ValueError(f"unknown training recipe {name!r}; known: {sorted(AEM_RECIPES)}")
    return replace(AEM_RECIPES[name], **overrides)


def window_vectors(windows: Windows, index: np.ndarray | slice | None = None) -> np.ndarray:
    """(b, D) float32: each window's module inputs and masks, flattened, padded slots zeroed."""
    a = windows.arrays(index)
    keep = a["context_mask"].astype(np.float32)  # (b, L)
    parts = []
    for name, mask in INPUT_ARRAYS:
        x = a[name].astype(np.float32)
        parts.append((x * keep.reshape(keep.shape + (1,) * (x.ndim - 2))).reshape(len(x), -1))
        if mask is not None:
            parts.append((a[mask] * keep[..., None]).reshape(len(x), -1).astype(np.float32))
    return np.concatenate(parts, axis=1)


class AutoEncoder(nn.Module):
    """MLP D → hidden… → latent → …hidden → D."""

    def __init__(self, dim: int, hidden: tuple[int, ...], latent: int) -> None:
        super().__init__()
        sizes = [dim, *hidden, latent]
        enc: list[nn.Module] = []
        dec: list[nn.Module] = []
        for a, b in zip(sizes[:-1], sizes[1:], strict=True):
            enc += [nn.Linear(a, b), nn.ReLU()]
        for a, b in zip(sizes[::-1][:-1], sizes[::-1][1:], strict=True):
            dec += [nn.Linear(a, b), nn.ReLU()]
        self.encoder = nn.Sequential(*enc[:-1])  # linear bottleneck
        self.decoder = nn.Sequential(*dec[:-1])  # linear output (standardised inputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # (B, D) → (B, D)
        return self.decoder(self.encoder(x))


@dataclass
class AEMMonitor:
    """A trained autoencoder with its input standardisation and error scale."""

    config: AEMConfig
    model: AutoEncoder
    mean: np.ndarray  # (D,)
    std: np.ndarray  # (D,)
    error_scale: float  # median reconstruction error on the training windows
    name: str = "aem"
    thresholds: Thresholds | None = None  # calibrated when a campaign trained it (meta.json)
    card: dict[str, Any] = field(default_factory=dict)  # meta.json of a saved version

    @property
    def context_len(self) -> int:
        return self.config.context_len

    @property
    def version(self) -> str:
        h = hashlib.sha256(json.dumps(self.config.record(), sort_keys=True).encode())
        for t in self.model.state_dict().values():
            h.update(t.detach().numpy().tobytes())
        h.update(self.mean.tobytes() + self.std.tobytes())
        return f"aem-{h.hexdigest()[:12]}"

    @intra_op_threads()
    def errors(self, windows: Windows) -> np.ndarray:
        """(B,) mean squared reconstruction error of each standardised window (one intra-op
        thread: exact scores, `evoeye.monitor.threads`)."""
        out = np.empty(len(windows), np.float64)
        self.model.eval()
        with torch.inference_mode():
            for start in range(0, len(windows), CHUNK):
                stop = min(start + CHUNK, len(windows))
                x = torch.from_numpy((window_vectors(windows, slice(start, stop)) - self.mean)
                                     / self.std)
                out[start:stop] = ((self.model(x) - x) ** 2).mean(dim=1).double().numpy()
        return out

    def score(self, windows: Windows) -> np.ndarray:
        e = self.errors(windows)
        return e / (e + self.error_scale)

    # -- persistence (torch.load(weights_only=True) reads it back) -------------------------------
    def save(self, folder: Path, meta: dict | None = None) -> Path:
        """Write `<folder>/<version>/model.pt` and `meta.json` (with `meta`, and the model's
        sha256); the version folder."""
        out = Path(folder) / self.version
        out.mkdir(parents=True, exist_ok=True)
        buf = io.BytesIO()
        torch.save({
            "config": self.config.record(),
            "state_dict": self.model.state_dict(),
            "mean": torch.from_numpy(self.mean),
            "std": torch.from_numpy(self.std),
            "error_scale": float(self.error_scale),
        }, buf)
        (out / MODEL_FILE).write_bytes(buf.getvalue())
        info = {"version": self.version, "name": self.name, "config": self.config.record(),
                "model_sha256": hashlib.sha256(buf.getvalue()).hexdigest()}
        (out / META_FILE).write_text(json.dumps({**info, **(meta or {})}, indent=2) + "\n")
        return out

    @classmethod
    def decode(cls, data: bytes, meta: dict[str, Any]) -> AEMMonitor:
        """The AEM of checked model.pt bytes (`torch.load(weights_only=True)`) and its meta.json,
        with the thresholds it records, if any."""
        blob = torch.load(io.BytesIO(data), weights_only=True)
        cfg = dict(blob["config"])
        cfg["hidden"] = tuple(cfg["hidden"])
        config = AEMConfig(**cfg)
        mean, std = blob["mean"].numpy(), blob["std"].numpy()
        model = AutoEncoder(len(mean), config.hidden, config.latent)
        model.load_state_dict(blob["state_dict"])
        thresholds = thresholds_from_card(meta) if "thresholds" in meta else None
        return cls(config, model, mean, std, float(blob["error_scale"]), thresholds=thresholds,
                   card=meta)

    @classmethod
    def load(cls, version_dir: Path) -> AEMMonitor:
        """The AEM saved in `version_dir`, checked against the sha256 in its meta.json (as a
        FusionMonitor against its card); MonitorLoadError if the hash is missing or differs."""
        return cls.decode(*read_version(version_dir, MODEL_FILE, META_FILE))


AfterEpoch = Callable[[int, int, "AEMMonitor"], None]  # epoch, optimiser steps, the AEM now


def train_aem(train: Windows, normal: np.ndarray, config: AEMConfig = AEMConfig(), *,
              init: AEMMonitor | None = None, threads: int = 1,
              after_epoch: AfterEpoch | None = None) -> AEMMonitor:
    """Fit the autoencoder on the windows `normal` (bool (B,)) of `train`; seeded by config
    (the same seed, data and thread count give the same weights). With `init`, fine-tune it:
    its weights and input standardisation are the start, only the error scale is re-measured.
    `after_epoch(epoch, steps, aem)` sees the AEM after every epoch and the optimiser steps
    taken (its error scale NaN, not yet measured: rank by `errors`), e.g. to follow a schedule's
    validation ranking; it changes no weight."""
    with intra_op_threads(threads):
        return _train(train, normal, config, init, after_epoch)


def _train(train: Windows, normal: np.ndarray, config: AEMConfig,
           init: AEMMonitor | None = None, after_epoch: AfterEpoch | None = None) -> AEMMonitor:
    if init is not None and (init.config.hidden, init.config.latent) != (config.hidden,
                                                                         config.latent):
        raise ValueError("a fine-tuned AEM keeps its parent's layer sizes")
    if train.context_len != config.context_len:
        raise ValueError(f"windows have L={train.context_len}, config wants {config.context_len}")
    idx = np.flatnonzero(np.asarray(normal, bool))
    if len(idx) == 0:
        raise ValueError("AEM needs at least one collision-free training window")
    rng = np.random.default_rng(config.seed)
    if len(idx) > config.max_train_windows:
        idx = np.sort(rng.choice(idx, config.max_train_windows, replace=False))
    x = np.concatenate([window_vectors(train, idx[s : s + CHUNK])
                        for s in range(0, len(idx), CHUNK)])
    if init is not None:
        mean, std = init.mean, init.std
    else:
        mean = x.mean(axis=0)
        std = x.std(axis=0)
        std = np.where(std > 1e-3, std, 1.0).astype(np.float32)
    xt = torch.from_numpy((x - mean) / std)

    torch.manual_seed(config.seed)
    model = AutoEncoder(x.shape[1], config.hidden, config.latent)
    if init is not None:
        model.load_state_dict(init.model.state_dict())
    opt = Adam(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    gen = torch.Generator().manual_seed(config.seed)
    lr_at = step_lrs(config.lr, config.schedule, config.warmup_epochs, config.epochs,
                     math.ceil(len(xt) / config.batch_size))
    step = 0
    for epoch in range(1, config.epochs + 1):
        model.train()
        for batch in torch.randperm(len(xt), generator=gen).split(config.batch_size):
            opt.lr = lr_at(step)
            step += 1
            xb = xt[batch]
            loss = ((model(xb) - xb) ** 2).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
        if after_epoch is not None:
            after_epoch(epoch, step,
                        AEMMonitor(config, model, mean.astype(np.float32), std, math.nan))
    model.eval()
    with torch.inference_mode():
        err = torch.cat([((model(c) - c) ** 2).mean(dim=1) for c in xt.split(CHUNK)])
    scale = max(float(err.median()), 1e-12)
    return AEMMonitor(config, model, mean.astype(np.float32), std, scale)
