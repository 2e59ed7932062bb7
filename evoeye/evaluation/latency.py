"""Inference cost on CPU: latency per context at batch 1 and throughput at batch 1024.

Timed end to end through `Monitor.score` (gathering the window's inputs included), with torch
on CPU; the first calls warm up caches and are not counted.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from evoeye.monitor.protocol import Monitor
from evoeye.store.windows import Windows

THROUGHPUT_BATCH = 1024


@dataclass(frozen=True)
class Latency:
    """Per-context latency (ms) at batch 1 and contexts per second at batch 1024."""

    latency_ms_median: float
    latency_ms_p95: float
    throughput_per_s: float
    batch: int
    calls: int
    torch_threads: int

    def to_dict(self) -> dict:
        return asdict(self)


def measure_latency(monitor: Monitor, windows: Windows, *, calls: int = 200,
                    batch: int = THROUGHPUT_BATCH, repeats: int = 5, seed: int = 0) -> Latency:
    """Time `monitor.score` on `calls` single windows and `repeats` batches of `batch`."""
    import torch

    if len(windows) == 0:
        raise ValueError("need windows to time a monitor on")
    rng = np.random.default_rng(seed)
    singles = [windows.subset(np.array([i])) for i in rng.integers(0, len(windows), calls + 10)]
    for w in singles[:10]:
        monitor.score(w)
    times_ms = []
    for w in singles[10:]:
        t0 = time.perf_counter()
        monitor.score(w)
        times_ms.append((time.perf_counter() - t0) * 1e3)
    big = windows.subset(rng.integers(0, len(windows), batch))
    monitor.score(big)
    t0 = time.perf_counter()
    for _ in range(repeats):
        monitor.score(big)
    elapsed = time.perf_counter() - t0
    return Latency(
        float(np.median(times_ms)), float(np.percentile(times_ms, 95)),
        batch * repeats / elapsed, batch, calls, torch.get_num_threads(),
    )
