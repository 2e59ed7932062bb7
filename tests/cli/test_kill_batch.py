"""Killing `evoeye simulate --workers 2`: the workers exit with it, and a re-run cleans up."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from evoeye.paths import DataRoot

pytestmark = [pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc"),
              pytest.mark.slow]  # two interpreters start highway-env: ≈ 20 s, more under load


def _stat(pid: int) -> list[str] | None:
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return text.rsplit(")", 1)[1].split()  # [state, ppid, …]


def _alive(pid: int) -> bool:
    stat = _stat(pid)
    return stat is not None and stat[0] not in ("Z", "X")  # a zombie has exited


def _children(pid: int) -> list[int]:
    pids = [int(p) for p in os.listdir("/proc") if p.isdigit()]
    return [p for p in pids if (s := _stat(p)) is not None and int(s[1]) == pid]


def _poll(condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.1)
    return condition()


def _simulate(root: Path, n: int, workers: int) -> list[str]:
    return [sys.executable, "-m", "evoeye", "simulate", "--scenario", "highway-cut-in",
            "--n", str(n), "--workers", str(workers), "--root", str(root)]


def test_sigkill_on_the_parent_ends_its_workers_and_a_rerun_cleans_up(tmp_path) -> None:
    root = tmp_path / "data"
    parent = subprocess.Popen(_simulate(root, 40, 2), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    workers: list[int] = []
    try:
        assert _poll(lambda: len(_children(parent.pid)) >= 2, 120.0), "no workers started"
        workers = _children(parent.pid)
        parent.send_signal(signal.SIGKILL)
        parent.wait(10)
        assert _poll(lambda: not any(_alive(w) for w in workers), 10.0), \
            [w for w in workers if _alive(w)]
    finally:
        parent.kill()
        for w in workers:  # on failure, leave no orphan behind
            if _alive(w):
                os.kill(w, signal.SIGKILL)
    batch = DataRoot.resolve(root).batch_dir("highway-cut-in", "uniform-seed0")
    batch.mkdir(parents=True, exist_ok=True)
    stale = batch / f"highway-cut-in-000000000000.mcap.{parent.pid}.tmp"  # its writer is dead
    stale.write_bytes(b"half a log")
    rerun = subprocess.run(_simulate(root, 3, 1), capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    assert not list(batch.glob("*.tmp")) and len(list(batch.glob("*.mcap"))) >= 3
    assert "removed the unfinished log" in rerun.stdout


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_stops_the_workers_says_what_was_kept_and_a_rerun_resumes(tmp_path) -> None:
    root = tmp_path / "data"
    batch = DataRoot.resolve(root).batch_dir("highway-cut-in", "uniform-seed0")
    # as from a shell: SIGINT at its default, so Python turns it into KeyboardInterrupt (a
    # pytest-xdist worker ignores SIGINT, and a child would inherit that)
    parent = subprocess.Popen(_simulate(root, 40, 2), stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, start_new_session=True,
                              preexec_fn=_default_sigint)
    workers: list[int] = []
    try:
        assert _poll(lambda: len(list(batch.glob("*.mcap"))) >= 2, 300.0), "no run finished"
        workers = _children(parent.pid)
        os.killpg(parent.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole group
        _, err = parent.communicate(timeout=60)
    finally:
        parent.kill()
        for w in workers:
            if _alive(w):
                os.kill(w, signal.SIGKILL)
    assert parent.returncode == 130, err
    assert len(workers) >= 2 and not any(_alive(w) for w in workers)  # nothing writes on
    assert "Traceback" not in err and "interrupted:" in err
    kept = len(list(batch.glob("*.mcap")))
    assert f"{kept} of the batch's 40 run logs are on disk" in " ".join(err.split())
    assert not list(batch.glob("*.tmp"))  # the runs in progress left nothing behind
    rerun = subprocess.run(_simulate(root, 40, 2), capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    assert len(list(batch.glob("*.mcap"))) == 40
    row = next(line for line in rerun.stdout.splitlines() if "highway-cut-in" in line
               and "│" in line)
    assert [c.strip() for c in row.split("│")][5] == str(kept)  # skipped: the kept ones
