"""How an epoch of training visits the windows (`TrainParams.batching`) and at what learning rate.

* "windows" (recipe v1): a random permutation of the windows cut into batches; each window is
  gathered with its L frames and runs through `FusionNet.forward`, so a frame is encoded once
  per window it sits in — L times per epoch.
* "chunks": the windows, in (run, frame) order, cut into chunks of `chunk_windows` consecutive
  windows at a random offset; the chunks are shuffled and cut into batches. A batch's windows
  then share their frames, and `FusionNet.forward_frames` encodes each distinct frame once: a
  chunk of c windows reads c + L − 1 frames, not c·L. The frames are tensors made once per
  training (on the training device), gathered per batch by row.

Both draw every random number from the training's generator, so a seed gives one order.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from evoeye.monitor.fusion import net_inputs
from evoeye.monitor.model import FRAME_INPUTS, FusionNet
from evoeye.monitor.recipes import TrainParams
from evoeye.store.windows import Windows


@dataclass
class Batch:
    """One batch's inputs on the training device, in the form its batching's `forward` takes,
    and its (b,) labels."""

    inputs: tuple
    label: torch.Tensor


class WindowBatches:
    """Batching "windows": random windows, each with its own L frames."""

    def __init__(self, train: Windows, params: TrainParams, device: torch.device) -> None:
        self.train, self.size, self.device = train, params.batch_size, device

    def steps(self) -> int:
        return math.ceil(len(self.train) / self.size)

    def epoch(self, gen: torch.Generator) -> list[np.ndarray]:
        """The epoch's batches of window indices."""
        order = torch.randperm(len(self.train), generator=gen).numpy()
        return [np.sort(order[start:start + self.size])  # sorted: faster gather
                for start in range(0, len(order), self.size)]

    def gather(self, index: np.ndarray) -> Batch:
        batch = self.train.batch(index)
        return Batch(tuple(t.to(self.device) for t in net_inputs(batch)),
                     batch.label.to(self.device))

    @staticmethod
    def forward(net: FusionNet, batch: Batch) -> torch.Tensor:
        return net(*batch.inputs)  # (b,) logits


class ChunkBatches:
    """Batching "chunks": shuffled chunks of consecutive windows, each frame encoded once."""

    def __init__(self, train: Windows, params: TrainParams, device: torch.device) -> None:
        self.train, self.size, self.chunk, self.device = (train, params.batch_size,
                                                          params.chunk_windows, device)
        arrays = train.features.arrays()
        self.frames = [torch.from_numpy(arrays[name]).to(device) for name in FRAME_INPUTS]
        self.context_mask = torch.from_numpy(train.context_mask).to(device)  # (B, L)
        self.label = torch.from_numpy(train.label.astype(np.float32)).to(device)  # (B,)

    def steps(self) -> int:
        return math.ceil(len(self.train) / self.size)

    def epoch(self, gen: torch.Generator) -> list[np.ndarray]:
        """The epoch's batches of window indices."""
        order = chunk_order(len(self.train), self.chunk, gen)
        return [order[start:start + self.size] for start in range(0, len(order), self.size)]

    def gather(self, index: np.ndarray) -> Batch:
        rows, inverse = self.train.distinct_frames(index)  # (U,), (b, L)
        at = torch.from_numpy(rows).to(self.device)
        windows = torch.from_numpy(index).to(self.device)
        return Batch(([f.index_select(0, at) for f in self.frames],
                      torch.from_numpy(inverse).to(self.device), self.context_mask[windows]),
                     self.label[windows])

    @staticmethod
    def forward(net: FusionNet, batch: Batch) -> torch.Tensor:
        return net.forward_frames(*batch.inputs)  # (b,) logits


def chunk_order(n: int, chunk: int, gen: torch.Generator) -> np.ndarray:
    """(n,) a permutation of range(n) made of runs of `chunk` consecutive indices: cut at a
    random offset (a first, shorter chunk), the chunks in random order."""
    offset = int(torch.randint(chunk, (1,), generator=gen)) if chunk > 1 else 0
    starts = np.r_[0, np.arange(offset or chunk, n, chunk)] if n else np.zeros(0, np.int64)
    lengths = np.diff(np.r_[starts, n])
    perm = torch.randperm(len(starts), generator=gen).numpy()
    starts, lengths = starts[perm], lengths[perm]
    # position within the order minus position within its chunk = the chunk's start there
    shift = np.repeat(starts - (np.cumsum(lengths) - lengths), lengths)
    return shift + np.arange(n)


BATCHINGS: dict[str, Callable[[Windows, TrainParams, torch.device],
                              WindowBatches | ChunkBatches]] = {
    "windows": WindowBatches,
    "chunks": ChunkBatches,
}

TAIL = 0.3  # "hold-decay": the share of the steps, at the end, over which lr falls to 0
SCHEDULES: dict[str, Callable[[float], float]] = {  # share of the decay done → factor of lr
    "constant": lambda done: 1.0,
    "cosine": lambda done: 0.5 * (1.0 + math.cos(math.pi * min(done, 1.0))),
    "hold-decay": lambda done: min(1.0, max(0.0, (1.0 - done) / TAIL)),
}


def lr_schedule(params: TrainParams, steps_per_epoch: int) -> Callable[[int], float]:
    """The learning rate of each optimiser step (0-based) of a training by `params`."""
    return step_lrs(params.lr, params.schedule, params.warmup_epochs, params.epochs,
                    steps_per_epoch)


def step_lrs(lr: float, schedule: str, warmup_epochs: float, epochs: int,
             steps_per_epoch: int) -> Callable[[int], float]:
    """The learning rate of each optimiser step (0-based): a linear warm-up from 0 to `lr`
    over `warmup_epochs`, then `schedule` (SCHEDULES) over the rest of `epochs`' steps."""
    warm = round(warmup_epochs * steps_per_epoch)
    decay = max(1, epochs * steps_per_epoch - warm)
    factor = SCHEDULES[schedule]

    def lr_at(step: int) -> float:
        if step < warm:
            return lr * (step + 1) / warm
        return lr * factor((step - warm) / decay)

    return lr_at
