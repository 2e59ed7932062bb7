"""The warehouse's single-writer lock: an exclusive `flock` on `<root>/warehouse/.writer.lock`.

The kernel drops the lock when its holder exits, however it exits, so a killed ingest never
leaves a stale lock behind. Readers take no lock (they read Parquet, never the DuckDB file).
"""

from __future__ import annotations

import fcntl
import os
import socket
import time
from pathlib import Path
from types import TracebackType
from typing import IO


class WarehouseLockedError(RuntimeError):
    """Another process holds the writer lock."""


class WriterLock:
    """Context manager holding the exclusive writer lock; raises WarehouseLockedError if held."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._file: IO[str] | None = None

    def __enter__(self) -> WriterLock:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        f = open(self.path, "a+", encoding="utf-8")  # noqa: SIM115 (held until __exit__)
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            holder = f.read().strip() or "unknown process"
            f.close()
            raise WarehouseLockedError(
                f"the warehouse {self.path.parent} is being written by another process "
                f"({holder}); only one writer at a time. Wait for it to finish and run again "
                f"(the lock on {self.path} is released when that process exits)."
            ) from None
        f.seek(0)
        f.truncate()
        f.write(f"pid {os.getpid()} on {socket.gethostname()} since {time.strftime('%FT%T%z')}")
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
            self._file.truncate(0)
            fcntl.flock(self._file.fileno(), fcntl.LOCK_UN)
            self._file.close()
            self._file = None
