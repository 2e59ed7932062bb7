"""How many intra-op threads torch uses while monitors train and score.

One: a monitor is small (a FusionMonitor has ~24 K parameters), so a second thread gains little
on an idle core, and when another process shares the cores — the normal case for a campaign,
which simulates between updates, or runs beside other campaigns — two threads collapse: scoring
one run's windows took ≈ 0.6 s instead of ≈ 7 ms on this project's 2-core machine under load.

Scoring always runs on one thread, whatever the caller set: `FusionMonitor.score` and
`score_batch` and the AEM's `errors` enter `intra_op_threads()` themselves. Exactness needs it,
not only speed: on some processors (an Intel Xeon, with MKL) torch's float32 kernels split
their sums by thread count, and scores with one thread and with two differed in the last bits
(3e-8), while the supervisor's pairing, replay against watch and cached scores compare scores
for equality. One thread gives one summation order on a given machine. (torch's OpenMP thread
count is per calling thread, so a scoring thread pins its own and restores it; the count is
left alone when it is already right, the common case, so threads that all score on one thread
never touch it.)
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
    if was == threads:
        yield
        return
    torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.set_num_threads(was)
