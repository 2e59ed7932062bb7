"""Run one function over several items at once, in forked processes, and collect the results.

Seeds of a monitor training are the use: the caller loads the data, then each seed trains in a
process forked from it, so every process starts with the data in shared memory and pays neither
loading nor start-up. Processes, not threads: a training step's work between torch kernels holds
Python's interpreter lock, so three threads on two cores lost a third of their time to each
other (BENCHMARKS.md). All items start at once unless `width` says fewer: on n cores k one-core
jobs time-shared end after ≈ k / n of one job's time, where waves of n take ⌈k / n⌉ of it.

A job may send messages (progress rows) while it runs: the parent passes each to `on_message`
as it arrives. A job's exception is raised in the parent, with the job's traceback; a job that
dies without a result (killed, out of memory) raises RuntimeError naming its item. Ctrl-C or
an error stops every job still running. Results travel back pickled by value (`pickle`), so a
result must pickle, and tensors in it come back as copies.
"""

from __future__ import annotations

import multiprocessing as mp
import pickle
import traceback
from collections.abc import Callable, Sequence
from multiprocessing.connection import Connection, wait
from typing import Any, TypeVar

T = TypeVar("T")
R = TypeVar("R")
Send = Callable[[Any], None]  # a job's channel to the parent's `on_message`


def can_fork() -> bool:
    """Whether jobs can run in forked processes here: the platform forks (Linux does; macOS and
    Windows spawn), and this process is not a daemon (a multiprocessing.Pool worker), which may
    not start processes of its own."""
    return "fork" in mp.get_all_start_methods() and not mp.current_process().daemon


def map_forked(job: Callable[[T, Send], R], items: Sequence[T], *, width: int | None = None,
               on_message: Callable[[T, Any], None] | None = None) -> list[R]:
    """[job(item, send) for item in items], each in a process forked from this one, at most
    `width` at a time (default: all); `on_message(item, message)` gets what a job sends."""
    ctx = mp.get_context("fork")
    width = max(1, width or len(items))
    results: list[Any] = [None] * len(items)
    waiting = list(range(len(items)))
    running: dict[Connection, tuple[int, mp.process.BaseProcess]] = {}
    try:
        while waiting or running:
            while waiting and len(running) < width:
                i = waiting.pop(0)
                theirs, ours = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_child, args=(job, items[i], ours), daemon=True)
                proc.start()
                ours.close()  # the child's end: EOF here once the child has gone
                running[theirs] = (i, proc)
            for conn in wait(list(running)):
                i, proc = running[conn]  # type: ignore[index]
                try:
                    kind, payload = pickle.loads(conn.recv_bytes())  # type: ignore[union-attr]
                except EOFError:
                    proc.join()
                    raise RuntimeError(f"the job for {items[i]!r} ended without a result (exit "
                                       f"code {proc.exitcode})") from None
                if kind == "message":
                    if on_message is not None:
                        on_message(items[i], payload)
                    continue
                del running[conn]  # type: ignore[arg-type]
                conn.close()  # type: ignore[union-attr]
                proc.join()
                if kind == "error":
                    raise payload
                results[i] = payload
    finally:
        for conn, (_, proc) in running.items():
            proc.terminate()
            proc.join()
            conn.close()
    return results


def _child(job: Callable[[T, Send], R], item: T, conn: Connection) -> None:
    """Run the job in the forked process and send back ("done", result) or ("error", exc)."""
    def send(kind: str, payload: Any) -> None:
        conn.send_bytes(pickle.dumps((kind, payload), protocol=pickle.HIGHEST_PROTOCOL))

    try:
        send("done", job(item, lambda message: send("message", message)))
    except BaseException as exc:  # noqa: BLE001 (the parent re-raises it)
        exc.add_note("".join(traceback.format_exception(exc)).rstrip())
        try:
            send("error", exc)
        except Exception:  # noqa: BLE001 (an exception that does not pickle)
            send("error", RuntimeError(f"{type(exc).__name__}: {exc}\n{exc.__notes__[-1]}"))
    finally:
        conn.close()
