"""Worker processes that end with their parent: a killed batch leaves no orphan behind, and an
interrupted one stops its workers at once.

On Linux the kernel sends the worker SIGKILL when its parent dies (`prctl(PR_SET_PDEATHSIG)`);
elsewhere a daemon thread polls the parent's pid. Pass `die_with_parent` as a process pool's
initializer with the parent's pid — or `stoppable_worker`, whose workers also leave Ctrl-C to
the parent and stop on `stop_workers` without finishing (or half-writing) the call they are in.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any, TypeVar

PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
POLL_S = 0.5
STOP_TIMEOUT_S = 1.5  # a stopped worker's time to unwind before SIGKILL
T = TypeVar("T")


def pool_context() -> mp.context.BaseContext:
    """The multiprocessing context worker pools start in."""
    # fork starts workers in milliseconds with highway-env already imported; spawn elsewhere.
    return mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")


def _watch(parent_pid: int) -> None:
    while os.getppid() == parent_pid:
        time.sleep(POLL_S)
    os.kill(os.getpid(), signal.SIGKILL)


def die_with_parent(parent_pid: int) -> None:
    """Make this (worker) process exit as soon as `parent_pid` is no longer its parent."""
    armed = False
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        armed = libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os.kill(os.getpid(), signal.SIGKILL)
    if not armed:
        threading.Thread(target=_watch, args=(parent_pid,), daemon=True).start()


# -- stopping a pool's workers at once, with nothing half-written ------------------------------
class _Stop(BaseException):
    """Raised in a busy worker by SIGTERM: it unwinds the call's `with` blocks (an atomic write
    removes its temporary file) before the worker exits."""


_busy = False  # whether this worker is inside a `stoppable` call


def _on_sigterm(signum: int, frame: object) -> None:
    if _busy:
        raise _Stop
    os._exit(128 + signum)


def stoppable_worker(parent_pid: int) -> None:
    """A process pool's initializer: the worker dies with its parent, leaves Ctrl-C (SIGINT)
    to the parent, and on SIGTERM stops at once, after unwinding the call in progress."""
    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _on_sigterm)


def stoppable(fn: Callable[..., T], *args: Any) -> T:
    """fn(*args), in a `stoppable_worker`: SIGTERM during it unwinds it and ends the worker."""
    global _busy
    _busy = True
    try:
        return fn(*args)
    except _Stop:
        os._exit(128 + signal.SIGTERM)
    finally:
        _busy = False


def stop_workers(pool: ProcessPoolExecutor, timeout_s: float = STOP_TIMEOUT_S) -> None:
    """Cancel the calls not started and SIGTERM the `stoppable_worker`s, which unwind the call
    in progress; SIGKILL any still alive after `timeout_s`."""
    workers = list((pool._processes or {}).values())  # Python ≥ 3.14: pool.terminate_workers()
    pool.shutdown(wait=False, cancel_futures=True)
    for w in workers:
        w.terminate()
    deadline = time.monotonic() + timeout_s
    for w in workers:
        w.join(max(0.0, deadline - time.monotonic()))
        if w.is_alive():
            w.kill()
            w.join()
