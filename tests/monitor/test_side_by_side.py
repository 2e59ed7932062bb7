"""Jobs in forked processes: results in order, messages passed on, failures raised, none left."""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from pathlib import Path

import numpy as np
import pytest

from evoeye.monitor.side_by_side import can_fork, map_forked

pytestmark = pytest.mark.skipif(not can_fork(), reason="processes start by fork only on Linux")


def test_results_come_back_in_order_with_every_message_of_each_job() -> None:
    data = np.arange(10.0)  # made before the fork: every job reads the parent's copy

    def job(k: int, send) -> tuple[int, float]:
        for step in range(k):
            send({"step": step})
        return os.getpid(), float(data[:k].sum())

    seen: list[tuple[int, dict]] = []
    out = map_forked(job, [3, 1, 4], on_message=lambda k, m: seen.append((k, m)))
    assert [total for _, total in out] == [3.0, 0.0, 6.0]
    assert len({pid for pid, _ in out} | {os.getpid()}) == 4  # three processes, none this one
    assert sorted(seen, key=lambda e: (e[0], e[1]["step"])) == [
        (k, {"step": s}) for k in (1, 3, 4) for s in range(k)]


def test_width_one_runs_the_jobs_one_after_the_other(tmp_path: Path) -> None:
    log = tmp_path / "log"

    def job(k: int, send) -> int:
        with open(log, "a") as f:
            f.write(f"start {k}\n")
        time.sleep(0.05)
        with open(log, "a") as f:
            f.write(f"end {k}\n")
        return k

    assert map_forked(job, [1, 2, 3], width=1) == [1, 2, 3]
    assert log.read_text().split("\n")[:-1] == [f"{e} {k}" for k in (1, 2, 3)
                                                for e in ("start", "end")]


def test_a_job_error_is_raised_with_its_traceback_and_stops_the_others() -> None:
    def job(k: int, send) -> int:
        if k == 2:
            raise ValueError(f"bad item {k}")
        time.sleep(30)  # would outlive the test unless stopped
        return k

    with pytest.raises(ValueError, match="bad item 2") as caught:
        map_forked(job, [1, 2, 3])
    assert any("in job" in note for note in caught.value.__notes__)
    assert mp.active_children() == []


def test_a_daemonic_process_cannot_fork_jobs_so_says_it_cannot() -> None:
    with mp.get_context("fork").Pool(1) as pool:  # a Pool's workers are daemons
        assert pool.apply(can_fork) is False
    assert can_fork()


def test_a_job_that_dies_without_a_result_is_named() -> None:
    def job(k: int, send) -> int:
        if k == "b":
            os._exit(3)
        return 0

    with pytest.raises(RuntimeError, match=r"'b' ended without a result \(exit code 3\)"):
        map_forked(job, ["a", "b"])
    assert mp.active_children() == []
