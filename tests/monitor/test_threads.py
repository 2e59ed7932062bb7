"""Monitors score on one intra-op thread, whatever the caller set: exact scores on every CPU
(`evoeye.monitor.threads`); and the caller's count is restored."""

from __future__ import annotations

import threading

import numpy as np
import pytest
import torch

from evoeye.baselines.aem import AEMConfig, train_aem
from evoeye.monitor import fusion
from evoeye.monitor.registry import load_monitor
from evoeye.monitor.threads import intra_op_threads
from evoeye.store import load_windows


@pytest.fixture
def threads_seen(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The intra-op thread count at every sigmoid the FusionMonitor's scoring takes."""
    seen: list[int] = []
    sigmoid = torch.sigmoid

    def recording(x: torch.Tensor) -> torch.Tensor:
        seen.append(torch.get_num_threads())
        return sigmoid(x)

    monkeypatch.setattr(fusion.torch, "sigmoid", recording)
    return seen


def test_fusion_scores_on_one_thread_whatever_the_caller_set(tiny, trained: str,
                                                             threads_seen: list[int]) -> None:
    monitor = load_monitor(tiny.root, trained)
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    scores, batches = {}, {}
    for threads in (2, 1):
        with intra_op_threads(threads):
            scores[threads] = monitor.score(windows)
            batches[threads] = monitor.score_batch(windows.batch(np.arange(64)))
            assert torch.get_num_threads() == threads  # the caller's count, restored
    assert threads_seen and set(threads_seen) == {1}
    assert len(windows) > 100 and np.ptp(scores[1]) > 0
    np.testing.assert_array_equal(scores[1], scores[2])
    np.testing.assert_array_equal(batches[1], batches[2])


def test_a_new_thread_scores_as_the_main_one(tiny, trained: str) -> None:
    """A task thread (Prefect's thread pool) starts with OpenMP's default count, not ours."""
    monitor = load_monitor(tiny.root, trained)
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    out: dict[str, np.ndarray] = {}

    def score() -> None:
        torch.set_num_threads(2)
        out["thread"] = monitor.score(windows)

    worker = threading.Thread(target=score)
    worker.start()
    worker.join()
    np.testing.assert_array_equal(out["thread"], monitor.score(windows))


def test_the_aem_scores_on_one_thread(tiny) -> None:
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    aem = train_aem(windows, windows.label == 0, AEMConfig(epochs=1))
    seen: list[int] = []
    aem.model.register_forward_pre_hook(lambda *_: seen.append(torch.get_num_threads()))
    with intra_op_threads(2):
        two = aem.score(windows)
    assert seen and set(seen) == {1}
    np.testing.assert_array_equal(two, aem.score(windows))


def test_the_thread_count_is_restored_as_a_decorator_too() -> None:
    before = torch.get_num_threads()

    @intra_op_threads(3)
    def inside() -> int:
        return torch.get_num_threads()

    assert inside() == 3 and torch.get_num_threads() == before
