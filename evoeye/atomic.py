"""Atomic file writes: a reader sees the old file or the complete new one, never a partial one.

A temporary file is named after its writer, `<name>.<pid>@<host>.tmp`, so that a data root
shared by several hosts can tell a dead writer's file from a live one's: this host's writers
are looked up by PID; another host's PIDs mean nothing here, so its file is taken for stale
only once untouched for `FOREIGN_STALE_S` (a log is written whole in seconds). Files of the
earlier `<name>.<pid>.tmp` form are judged by PID, as they were.
"""

from __future__ import annotations

import os
import re
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

FOREIGN_STALE_S = 3600.0  # another host's temporary file untouched this long is a dead writer's
_TEMP = re.compile(r"\.(?P<pid>\d+)(?:@(?P<host>[A-Za-z0-9_-]+))?\.tmp$")


def host_tag() -> str:
    """This host's name as it goes into temporary file names (letters, digits, '_', '-')."""
    return re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname()) or "host"


def temp_path(path: Path) -> Path:
    """The default temporary name next to `path`: `<name>.<pid>@<host>.tmp` (never taken for
    data)."""
    return path.with_name(f"{path.name}.{os.getpid()}@{host_tag()}.tmp")


@contextmanager
def atomic_file(path: Path, tmp: Path | None = None) -> Iterator[BinaryIO]:
    """Write to a temporary file beside `path`; on success flush, fsync and rename it over `path`.

    On any error (or interruption) the temporary file is removed and the error re-raised; a killed
    process leaves only the temporary file behind.
    """
    tmp = tmp or temp_path(path)
    try:
        with open(tmp, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    return True


def is_stale(tmp: Path, now: float | None = None) -> bool:
    """Whether the writer of temporary file `tmp` is gone (module doc); False for a name that is
    not a writer's."""
    m = _TEMP.search(tmp.name)
    if m is None:
        return False
    pid, host = int(m["pid"]), m["host"]
    if host is None or host == host_tag():
        return pid != os.getpid() and not _alive(pid)
    try:
        age_s = (time.time() if now is None else now) - tmp.stat().st_mtime
    except FileNotFoundError:  # its writer finished (renamed it) or removed it meanwhile
        return False
    return age_s > FOREIGN_STALE_S


def remove_stale_temps(folder: Path) -> list[Path]:
    """Remove the temporary files in `folder` whose writer is gone (`is_stale`); them."""
    if not folder.is_dir():
        return []
    stale = []
    for tmp in folder.glob("*.tmp"):
        if is_stale(tmp):
            tmp.unlink(missing_ok=True)
            stale.append(tmp)
    return sorted(stale)


def fsync_dir(folder: Path) -> None:
    """Make a rename inside `folder` durable (the directory entry itself is fsynced)."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
