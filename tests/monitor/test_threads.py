"""One intra-op thread while monitors score: the same scores as two, and the count restored."""

from __future__ import annotations

import numpy as np
import torch

from evoeye.monitor.registry import load_monitor
from evoeye.monitor.threads import intra_op_threads
from evoeye.store import load_windows


def test_scores_do_not_depend_on_the_thread_count(tiny, trained: str) -> None:
    monitor = load_monitor(tiny.root, trained)
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    scores = {}
    for threads in (2, 1):
        with intra_op_threads(threads):
            assert torch.get_num_threads() == threads
            scores[threads] = monitor.score(windows)
    assert len(windows) > 100 and np.ptp(scores[1]) > 0
    np.testing.assert_array_equal(scores[1], scores[2])


def test_the_thread_count_is_restored_as_a_decorator_too() -> None:
    before = torch.get_num_threads()

    @intra_op_threads(3)
    def inside() -> int:
        return torch.get_num_threads()

    assert inside() == 3 and torch.get_num_threads() == before
