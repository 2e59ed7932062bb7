"""Ingest with logs read in worker processes: the same warehouse as one process, bad logs still
quarantined by name, and no worker left behind."""

from __future__ import annotations

import multiprocessing as mp
from dataclasses import replace

import pyarrow as pa
import pytest

from evoeye.log import LogError
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest
from evoeye.store.reading import MIN_LOGS_PER_WORKER, read_logs

WORKERS = 2
N_RUNS = MIN_LOGS_PER_WORKER * WORKERS + 2  # enough for the pool to be used
# what differs between two ingests of the same logs: the part a row is in, and when
VOLATILE = ("ingest_id", "ingested_at")


def _fill(root: DataRoot, make_episode, write_run) -> dict[str, str]:
    """N_RUNS logs (some colliding, one of a world variant, one truncated, one corrupt); the
    bad ones' relative paths → what their reason must contain."""
    logs = []
    for i in range(N_RUNS):
        ep = make_episode(f"w-{i:02d}", n_frames=8 + i % 5, seed=i,
                          collision_frame=5 if i % 3 == 0 else None, batch=f"b{i % 2}")
        if i == 4:
            ep.spec = replace(ep.spec, world="follower")
        logs.append(write_run(root, ep))
    truncated, corrupt = logs[7], logs[11]
    truncated.write_bytes(truncated.read_bytes()[: truncated.stat().st_size // 2])
    data = bytearray(corrupt.read_bytes())
    data[len(data) // 3: len(data) // 3 + 64] = b"\x00" * 64  # inside a chunk: CRC fails
    corrupt.write_bytes(bytes(data))
    return {root.relative(truncated): "truncated", root.relative(corrupt): "corrupt"}


def _table(root: DataRoot, view: str) -> pa.Table:
    t = Warehouse(root).sql(f"SELECT * FROM {view} ORDER BY scenario_id"
                            + (", frame" if view != "scenarios" else ""))
    return t.drop_columns([c for c in VOLATILE if c in t.column_names])


def test_workers_write_the_same_warehouse_and_quarantine_the_same_logs(
        tmp_path, episode_factory, log_writer) -> None:
    one, pool = (DataRoot.resolve(tmp_path / name) for name in ("one", "pool"))
    bad = _fill(one, episode_factory, log_writer)
    assert _fill(pool, episode_factory, log_writer) == bad
    reports = [ingest(one, runs_per_part=4), ingest(pool, runs_per_part=4, workers=WORKERS)]
    for report in reports:
        assert len(report.ingested) == N_RUNS - 3  # the variant's left out, two quarantined
        assert report.left_out == ["runs/highway-cut-in/b0/w-04.mcap"]
        reasons = dict(report.quarantined)
        assert sorted(reasons) == sorted(bad)
        assert "truncated" in reasons[next(p for p, why in bad.items() if why == "truncated")]
    a, b = reports
    assert a.ingested == b.ingested and a.frames == b.frames
    for view in ("scenarios", "frames", "frame_features"):
        assert _table(one, view).equals(_table(pool, view)), view
    again = ingest(pool, workers=WORKERS)  # idempotent with workers too
    assert not again.ingested and again.skipped == N_RUNS - 3 and not again.quarantined


def test_a_reader_stopped_early_leaves_no_worker_behind(tmp_path, episode_factory,
                                                        log_writer) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    logs = [log_writer(root, episode_factory(f"s-{i:02d}", n_frames=6, seed=i))
            for i in range(N_RUNS)]
    reads = read_logs(logs, WORKERS)
    first_log, first = next(reads)
    meta, run = first.result()
    assert first_log == logs[0] and meta["scenario_id"] == "s-00" and run.frames.num_rows == 6
    assert len(mp.active_children()) == WORKERS  # read in a pool
    reads.close()  # e.g. the ingest failed or was interrupted
    assert mp.active_children() == []


def test_a_bad_log_read_in_a_worker_raises_where_its_result_is_taken(tmp_path, episode_factory,
                                                                     log_writer) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    logs = [log_writer(root, episode_factory(f"e-{i:02d}", n_frames=6, seed=i))
            for i in range(N_RUNS)]
    logs[3].write_bytes(b"not a log")
    results = list(read_logs(logs, WORKERS))
    assert [log for log, _ in results] == logs  # in the logs' order
    with pytest.raises(LogError, match=logs[3].name):
        results[3][1].result()
    assert all(fut.exception() is None for i, (_, fut) in enumerate(results) if i != 3)


def test_workers_below_one_are_refused(root: DataRoot) -> None:
    with pytest.raises(ValueError, match="workers must be at least 1"):
        ingest(root, workers=0)
