"""The warehouse's writer locks: `flock`s on `<root>/warehouse/.writer.lock` and on key stripes.

A writer that may touch anything — a full ingest, which also removes the parts of killed
ingests in every partition — holds `.writer.lock` exclusively. A writer of a few keys only (a
campaign committing its runs, storing feedback under its own monitor versions, its rounds) holds
it shared, so such writers never wait for one another, and locks just its keys exclusively: each
key hashes to one of `STRIPES` stripe files per table under `.locks/`, taken in sorted order (no
deadlock), waited for (another writer of the same stripe holds it for one short write).

The kernel drops a lock when its holder exits, however it exits, so a killed writer never leaves
a stale lock behind. Readers take no lock (they read Parquet, never the DuckDB file).
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import socket
import time
from collections.abc import Iterable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from types import TracebackType
from typing import IO

from evoeye.paths import DataRoot

STRIPES = 256  # lock files per table for keyed writes
LOCKS_DIR = ".locks"


class WarehouseLockedError(RuntimeError):
    """Another process holds the writer lock."""


class WriterLock:
    """Context manager holding a lock on `path`: exclusive (the default) or `shared`; raises
    WarehouseLockedError if it is held in a conflicting mode, unless `wait`."""

    def __init__(self, path: Path, *, shared: bool = False, wait: bool = False) -> None:
        self.path = Path(path)
        self.shared = shared
        self.wait = wait
        self._file: IO[str] | None = None

    def __enter__(self) -> WriterLock:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        f = open(self.path, "a+", encoding="utf-8")  # noqa: SIM115 (held until __exit__)
        mode = fcntl.LOCK_SH if self.shared else fcntl.LOCK_EX
        try:
            fcntl.flock(f.fileno(), mode if self.wait else mode | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            holder = f.read().strip() or "writers of single keys, e.g. a campaign"
            f.close()
            raise WarehouseLockedError(
                f"the warehouse {self.path.parent} is being written by another process "
                f"({holder}); only one writer at a time. Wait for it to finish and run again "
                f"(the lock on {self.path} is released when that process exits)."
            ) from None
        if not self.shared:  # a shared holder must not overwrite the others' line
            f.seek(0)
            f.truncate()
            f.write(f"pid {os.getpid()} on {socket.gethostname()} since "
                    f"{time.strftime('%FT%T%z')}")
            f.flush()
        self._file = f
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._file is not None:
            if not self.shared:
                self._file.truncate(0)
            fcntl.flock(self._file.fileno(), fcntl.LOCK_UN)
            self._file.close()
            self._file = None


def stripe_path(root: DataRoot, table: str, key: str) -> Path:
    """The lock file of the stripe `key` of `table` falls in."""
    stripe = int(hashlib.sha1(key.encode()).hexdigest()[:8], 16) % STRIPES
    return root.warehouse / LOCKS_DIR / f"{table}-{stripe:03d}.lock"


@contextmanager
def key_lock(root: DataRoot, table: str, keys: Iterable[str]) -> Iterator[None]:
    """Write access to `keys` of `table`: the writer lock shared (WarehouseLockedError while an
    exclusive writer holds it) and the keys' stripes exclusively, waited for, in sorted order.
    Take all of one table's keys in one call: a nested call whose key shares a stripe with a
    held one would wait for its own process."""
    with ExitStack() as stack:
        stack.enter_context(WriterLock(root.writer_lock, shared=True))
        for path in sorted({stripe_path(root, table, k) for k in keys}):
            stack.enter_context(WriterLock(path, wait=True))
        yield
