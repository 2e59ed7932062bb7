"""Temporary files name their writer's host and PID; only a gone writer's are removed."""

from __future__ import annotations

import os
import subprocess
import sys
import time

from evoeye.atomic import FOREIGN_STALE_S, host_tag, remove_stale_temps, temp_path


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_temporary_name_carries_pid_and_host(tmp_path) -> None:
    name = temp_path(tmp_path / "run.mcap").name
    assert name == f"run.mcap.{os.getpid()}@{host_tag()}.tmp"
    assert "." not in host_tag()


def test_only_gone_writers_files_are_removed(tmp_path) -> None:
    dead, alive, me = _dead_pid(), os.getppid(), host_tag()
    files = {
        "mine-dead": f"a.mcap.{dead}@{me}.tmp",
        "mine-alive": f"b.mcap.{alive}@{me}.tmp",
        "legacy-dead": f"c.mcap.{dead}.tmp",
        "foreign-fresh": f"d.mcap.{dead}@{me}x-other.tmp",  # its PID means nothing here
        "foreign-old": f"e.mcap.{alive}@{me}x-other.tmp",
        "not-a-writers": "f.mcap.tmp",
    }
    for name in files.values():
        (tmp_path / name).write_bytes(b"half a log")
    old = time.time() - FOREIGN_STALE_S - 60
    os.utime(tmp_path / files["foreign-old"], (old, old))
    removed = {p.name for p in remove_stale_temps(tmp_path)}
    assert removed == {files[k] for k in ("mine-dead", "legacy-dead", "foreign-old")}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        files[k] for k in ("mine-alive", "foreign-fresh", "not-a-writers"))
