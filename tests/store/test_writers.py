"""Writers of single keys: their own lock stripes under a shared writer lock, their own parts."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.store import WarehouseLockedError, WriterLock
from evoeye.store.derived import part_name
from evoeye.store.feedback import FeedbackRows, read_feedback, write_feedback
from evoeye.store.lock import key_lock, stripe_path


def test_writers_of_other_keys_go_on_while_a_full_writer_excludes_them(root: DataRoot) -> None:
    a, b = "fusion-a", next(f"fusion-{i}" for i in range(100)
                            if stripe_path(root, "feedback", f"fusion-{i}")
                            != stripe_path(root, "feedback", "fusion-a"))
    with key_lock(root, "feedback", [a]):
        with key_lock(root, "feedback", [b]):  # another stripe: no wait
            pass
        with (pytest.raises(WarehouseLockedError, match="writers of single keys"),
              WriterLock(root.writer_lock)):  # e.g. a full ingest
            pass
    with (WriterLock(root.writer_lock), pytest.raises(WarehouseLockedError, match="pid"),
          key_lock(root, "feedback", [a])):
        pass


def test_a_writer_of_the_same_key_waits_for_the_holder(root: DataRoot) -> None:
    held, order = threading.Event(), []

    def holder() -> None:
        with key_lock(root, "feedback", ["fusion-a"]):
            held.set()
            time.sleep(0.3)
            order.append("holder done")

    thread = threading.Thread(target=holder)
    thread.start()
    held.wait(5)
    with key_lock(root, "feedback", ["fusion-a"]):
        order.append("waiter in")
    thread.join()
    assert order == ["holder done", "waiter in"]


def test_a_key_reads_its_own_parts_only(root: DataRoot) -> None:
    for version in ("fusion-a", "fusion-b"):
        write_feedback(root, FeedbackRows("highway-cut-in", version, "raw",
                                          np.array(["r-1"], object), np.array([0.5]),
                                          np.array([3])))
    folder = root.table_dir("feedback")
    names = sorted(p.name for p in folder.iterdir())
    assert [n.split("--")[0] for n in names] == ["fusion-a", "fusion-b"]
    (folder / names[1]).write_bytes(b"not parquet")  # fusion-b's part, broken
    assert read_feedback(root, "fusion-a").column("scenario_id").to_pylist() == ["r-1"]
    with pytest.raises(Exception, match="parquet|Parquet"):
        read_feedback(root)  # every part is opened


def test_a_key_must_name_a_file_and_hold_no_separator() -> None:
    from datetime import UTC, datetime

    now = datetime.now(UTC)
    assert part_name(now, "evo-no-feedback-s0-1a2b").startswith("evo-no-feedback-s0-1a2b--part-")
    for bad in ("a--b", "../x", "", "a/b"):
        with pytest.raises(ValueError, match="cannot key a part"):
            part_name(now, bad)
