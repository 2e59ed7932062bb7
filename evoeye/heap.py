"""A long job's start-up heap, left out of the cyclic garbage collector's full passes.

A campaign's process holds ≈ 400 k objects the collector tracks once torch, numba, highway-env
and the warehouse code are loaded, and every full (generation 2) collection walks all of them:
≈ 0.15–0.2 s each, a few per round, mostly while the round simulates and converts its runs.
None of them becomes garbage while the job runs. `frozen_heap()` moves the objects alive at its
start to the collector's permanent generation (`gc.freeze`) and back at its end, so the
collections in between walk only what the job itself made. Reference counting still frees
what it always frees; only reference cycles among the frozen objects wait for the block's end.
"""

from __future__ import annotations

import gc
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_depth = 0  # frozen_heap blocks open in this process (gc.unfreeze thaws every frozen object)
_lock = threading.Lock()


@contextmanager
def frozen_heap() -> Iterator[None]:
    """Within the block, full collections skip the objects alive when the outermost block began."""
    global _depth
    with _lock:
        if _depth == 0:
            gc.freeze()
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                gc.unfreeze()
