"""How many intra-op threads torch uses while monitors train and score.

One: a monitor is small (a FusionMonitor has ~24 K parameters), so a second thread gains little
on an idle core, and when another process shares the cores — the normal case for a campaign,
which simulates between updates, or runs beside other campaigns — two threads collapse: scoring
one run's windows took ≈ 0.6 s instead of ≈ 7 ms on this project's 2-core machine under load.
The scores are the same with one thread or two (tests/monitor/test_threads.py).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

MONITOR_THREADS = 1


@contextmanager
def intra_op_threads(threads: int = MONITOR_THREADS) -> Iterator[None]:
    """torch's intra-op thread count set to `threads`, restored after (also as a decorator)."""
    import torch

    was = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.set_num_threads(was)
