"""Run logs read for ingest: one after another in this process, or in a pool of worker processes.

Reading is most of an ingest's cost (decoding the messages' JSON, building the frames table and
its features: ≈ 90 ms a highway run, against ≈ 4 ms to write it), and each log is read on its
own, so `workers` processes read logs side by side while the ingesting process writes parts in
the logs' order. What is written does not depend on the number of workers: each log gives the
same frames and features either way (tests/store/test_ingest_workers.py).

A log that cannot be ingested (`LogError`, `RunRecordError`) comes back as that error, raised
where its result is taken, so the ingest quarantines it and goes on; a log of a world variant
is not converted (the ingest leaves it out).
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, wait
from pathlib import Path

from evoeye.lifeline import die_with_parent, pool_context
from evoeye.log import read_run
from evoeye.sim.worlds import DEFAULT_WORLD
from evoeye.store.log_windows import LoggedRun, frames_of
from evoeye.store.metadata import check_metadata
from evoeye.store.records import FRAME_CLOCK, frame_column_sources

AHEAD_PER_WORKER = 4  # logs read ahead of the writer per worker: bounds the memory held
MIN_LOGS_PER_WORKER = 8  # below this a pool's start-up is not worth it: read in this process


def ingest_topics() -> list[str]:
    """The topics a log's frames are built from (the rest of a log is not decoded)."""
    return sorted({FRAME_CLOCK, *(t for t, _ in frame_column_sources().values())})


def read_for_ingest(log: Path) -> tuple[dict, LoggedRun | None]:
    """A log's metadata (checked) and its conversion as ingest writes it: its frames (in no
    part yet) and their features; None for a world variant's run, which is not ingested."""
    source = read_run(log, topics=ingest_topics())
    meta = dict(source.metadata)
    check_metadata(meta)
    if meta.get("world", DEFAULT_WORLD) != DEFAULT_WORLD:
        return meta, None
    return meta, frames_of(source, log)


def read_logs(logs: Sequence[Path], workers: int = 1) -> Iterator[tuple[Path, Future]]:
    """(log, the finished future of `read_for_ingest(log)`) in the logs' order; taking its
    result raises what reading that log raised. With `workers` > 1 (and enough logs) the logs
    are read in a pool of that many processes, a bounded number ahead of the caller."""
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if workers == 1 or len(logs) < MIN_LOGS_PER_WORKER * workers:
        for log in logs:
            yield log, _done(read_for_ingest, log)
        return
    pool = ProcessPoolExecutor(workers, mp_context=pool_context(), initializer=die_with_parent,
                               initargs=(os.getpid(),))
    try:
        ahead: deque[tuple[Path, Future]] = deque()
        for log in logs:
            ahead.append((log, pool.submit(read_for_ingest, log)))
            if len(ahead) >= AHEAD_PER_WORKER * workers:
                yield _finished(*ahead.popleft())
        while ahead:
            yield _finished(*ahead.popleft())
    finally:  # also when the caller stops early (an error, Ctrl-C): nothing left to read
        pool.shutdown(wait=True, cancel_futures=True)


def _finished(log: Path, fut: Future) -> tuple[Path, Future]:
    wait([fut])
    return log, fut


def _done(fn, *args) -> Future:
    """A finished future holding fn(*args) or the exception it raised."""
    fut: Future = Future()
    try:
        fut.set_result(fn(*args))
    except Exception as e:  # noqa: BLE001 - raised again where the result is taken
        fut.set_exception(e)
    return fut
