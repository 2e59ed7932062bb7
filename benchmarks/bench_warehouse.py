"""Warehouse throughput: ingest vs bare MCAP decoding; window extraction vs in-memory numpy.

Ingest (target ≤ 2×): `--runs` synthetic runs shaped like the ADS's (400 frames at 20 Hz,
6 obstacles, K = 30 predicted and P = 41 planned points; one run in COLLIDE_EVERY collides 3/4 of
the way in, the others never) are written as MCAP logs, then
  bare    read_run + JSON-decode every message of the topics the warehouse keeps, and nothing else
  ingest  one full `evoeye ingest` pass over the same logs: decode, convert, monitor features,
          three Parquet parts per partition written atomically, commit, catalog refresh.
Then the same pass with each of `--workers` processes reading the logs (`ingest(workers=N)`):
wall seconds and CPU seconds of this process and its workers, and the speed-up over one
process (target on 2 cores: ≥ 1.6×; the warehouse is the same either way).

Windows (target ≤ 2×): the ingested parts are replicated under new scenario ids until the
warehouse holds ≥ `--window-frames` frames (content does not change the cost; every replica
is an ordinary committed run). Windows end at the eligible frames only (none at or after a
collision). Both sides produce the same arrays, (B, L, …) for every frame:
  warehouse  load_windows(L) — the runs and their parts from SQL, each part's frames columns and
             float32 inputs read by Arrow, labels in numpy, the inputs copied once in window
             order — then Windows.arrays(), the gather of all B windows
  numpy      the per-frame inputs already in memory in (scenario, frame) order with the run
             lengths: context index and mask by numpy, then the same gather.
Every timing is the best of `--repeat` (the machine may be shared).
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from benchmarks.machine import describe
from evoeye.log import read_run, write_episode
from evoeye.log.synthetic import synthetic_episode, with_collision
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest, load_windows
from evoeye.store.ingest import discover_logs
from evoeye.store.parts import PartStore
from evoeye.store.reading import ingest_topics
from evoeye.store.schema import PARTITION_KEYS, TABLES

COLLIDE_EVERY = 10  # one run in ten collides; its frames from the collision on are no windows


def best_of(repeat: int, fn: Callable[[], object], before: Callable[[], None] = lambda: None
            ) -> tuple[float, object]:
    """(best wall seconds, last result) of `repeat` calls, `before` run untimed each time."""
    best, result = float("inf"), None
    for _ in range(repeat):
        before()
        result = None  # free the previous result before timing the next
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def write_logs(root: DataRoot, runs: int, frames: int) -> list[Path]:
    for seed in range(runs):
        collision = frames * 3 // 4 if seed % COLLIDE_EVERY == 0 else None
        ep = with_collision(synthetic_episode(frames, seed=seed), collision)
        path = root.run_log(ep.spec.scenario, ep.spec.batch, ep.spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_episode(ep, path)
    return discover_logs(root.runs)


def bare_decode(logs: list[Path], topics: list[str]) -> int:
    n = 0
    for log in logs:
        run = read_run(log, topics=topics)
        for topic in topics:
            n += len(run.messages(topic))
    return n


def reset_warehouse(root: DataRoot) -> None:
    for table in TABLES:
        for path in root.table_dir(table).rglob("*.parquet"):
            path.unlink()


def _renamed(table: pa.Table, column: str, suffix: str) -> pa.Table:
    i = table.schema.get_field_index(column)
    return table.set_column(i, column, pc.binary_join_element_wise(table[column], suffix, ""))


def replicate(root: DataRoot, min_frames: int) -> int:
    """Copy the committed parts under new scenario ids until ≥ min_frames frames; the total."""
    store = PartStore(root)
    sources = sorted(root.table_dir("scenarios").rglob("*.parquet"))
    base = sum(pq.read_metadata(root.table_dir("frames") / p.relative_to(
        root.table_dir("scenarios"))).num_rows for p in sources)
    copies = -(-min_frames // base) - 1
    for c in range(copies):
        for src in sources:
            rel = src.relative_to(root.table_dir("scenarios"))
            partition = tuple(part.split("=", 1)[1] for part in rel.parts[: len(PARTITION_KEYS)])
            part = f"{src.stem}-copy{c:04d}"
            for table in ("frames", "frame_features", "scenarios"):  # scenarios last: commit
                data = pq.read_table(root.table_dir(table) / rel)
                data = _renamed(data, "scenario_id", f"-copy{c}")
                data = data.set_column(data.schema.get_field_index("ingest_id"), "ingest_id",
                                       pa.array([part] * data.num_rows))
                if table == "scenarios":
                    data = _renamed(data, "log_path", f"-copy{c}")
                store.write(table, partition, part, data)
    return base * (copies + 1)


def _cpu_s() -> float:
    """CPU seconds of this process and of its finished children."""
    return sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))


def ingest_workers(root: DataRoot, runs: int, repeat: int, workers: list[int]) -> None:
    """The ingest pass with logs read by 1 and by each of `workers` processes (best wall of
    `repeat`, and the CPU seconds of that pass)."""
    print("| ingest, logs read by | runs | wall s | CPU s (all processes) | speed-up (wall) |")
    print("|---|---|---|---|---|")
    base = None
    for n in sorted({1, *workers}):
        best = (float("inf"), 0.0)
        for _ in range(repeat):
            reset_warehouse(root)
            t0, c0 = time.perf_counter(), _cpu_s()
            ingest(root, workers=n)
            best = min(best, (time.perf_counter() - t0, _cpu_s() - c0))
        base = base or best[0]
        print(f"| {n} process{'es' if n > 1 else ''} | {runs} | {best[0]:.2f} | {best[1]:.2f} "
              f"| {base / best[0]:.2f}× |")
    print()


def numpy_windows(frames: dict[str, np.ndarray], run_lengths: np.ndarray, context_len: int
                  ) -> dict[str, np.ndarray]:
    """The same windows from per-frame arrays in (scenario, frame) order, by numpy alone."""
    starts = np.repeat(np.cumsum(run_lengths) - run_lengths, run_lengths)
    pos = np.arange(len(starts)) - starts
    back = pos[:, None] - context_len + 1 + np.arange(context_len)[None, :]
    index = starts[:, None] + np.maximum(back, 0)
    out = {name: np.take(arr, index, axis=0) for name, arr in frames.items()}
    out["context_mask"] = back >= 0
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=100, help="runs written and ingested")
    ap.add_argument("--frames", type=int, default=400, help="frames per run (20 s at 20 Hz)")
    ap.add_argument("--window-frames", type=int, default=500_000)
    ap.add_argument("--context-len", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, nargs="*", default=[2],
                    help="processes reading logs in the side-by-side ingest (1 is the reference)")
    args = ap.parse_args()
    print(f"Machine: {describe()}\n")
    with tempfile.TemporaryDirectory(prefix="bench-warehouse-") as tmp:
        root = DataRoot.resolve(tmp)
        logs = write_logs(root, args.runs, args.frames)
        topics = ingest_topics()
        bare_s, _ = best_of(args.repeat, lambda: bare_decode(logs, topics))
        ingest_s, report = best_of(args.repeat, lambda: ingest(root),
                                   before=lambda: reset_warehouse(root))
        n = report.frames
        print("| ingest | runs | frames | bare read+decode s | ingest s | bare frames/s "
              "| ingest frames/s | ingest / bare |")
        print("|---|---|---|---|---|---|---|---|")
        print(f"| {args.runs} × {args.frames} frames | {args.runs} | {n:,} | {bare_s:.2f} "
              f"| {ingest_s:.2f} | {n / bare_s:,.0f} | {n / ingest_s:,.0f} "
              f"| {ingest_s / bare_s:.2f}× |\n")
        ingest_workers(root, args.runs, args.repeat, args.workers)

        total = replicate(root, args.window_frames)
        L = args.context_len
        load_s, windows = best_of(args.repeat, lambda: load_windows(root, context_len=L))
        gather_s, ours = best_of(args.repeat, windows.arrays)
        eligible = Warehouse(root).sql("SELECT count(*) FROM eligible_frames")[0][0].as_py()
        assert len(windows) == eligible
        # the numpy side starts from the same frames, in (scenario, frame) order, in memory
        frames = {k: v[windows.context[:, -1]] for k, v in windows.features.arrays().items()}
        _, run_lengths = np.unique(windows.scenario_id, return_counts=True)
        numpy_s, theirs = best_of(args.repeat, lambda: numpy_windows(frames, run_lengths, L))
        for name, arr in theirs.items():
            assert np.array_equal(arr, ours[name]), name  # the very same windows
        parquet_mb = sum(p.stat().st_size for p in root.table_dir("frame_features").rglob(
            "*.parquet")) / 2**20
        window_gb = sum(v.nbytes for v in ours.values()) / 2**30
        ratio = (load_s + gather_s) / numpy_s
        print(f"| windows L = {L} | frames | eligible | runs | frame_features MiB | load_windows s "
              f"| gather s | warehouse total s | numpy s | warehouse / numpy | target ≤ 2× |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        print(f"| ({window_gb:.1f} GiB of arrays) | {total:,} | {eligible:,} "
              f"| {Warehouse(root).sql('SELECT count(*) FROM scenarios')[0][0]} "
              f"| {parquet_mb:,.0f} | {load_s:.2f} | {gather_s:.2f} | {load_s + gather_s:.2f} "
              f"| {numpy_s:.2f} | {ratio:.2f}× | {'yes' if ratio <= 2 else 'no'} |")


if __name__ == "__main__":
    main()
