"""The appended tables' views: what they cost a connection, with many parts.

`--parts` one-row parts are written to each of monitor_scores, feedback and campaign_rounds
(an experiment writes thousands, keyed), then, in CPU time (`time.process_time`, the machine may
be shared), the mean over `--repeat` calls of
  connect  `Warehouse.connect()`: the code's connection (views it reads; no appended table's but
           attribution's)
  user     `Warehouse.read_only_sql("SELECT 1")`: `evoeye sql`'s connection, every view bound
  count    `Warehouse.read_only_sql("SELECT count(*) FROM feedback")`: a query over all parts.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from benchmarks.machine import describe
from evoeye.paths import DataRoot
from evoeye.store import Warehouse
from evoeye.store.schema import declared_schema

TABLES = ("monitor_scores", "feedback", "campaign_rounds")


def write_parts(root: DataRoot, parts: int) -> None:
    """`parts` keyed one-row parts per table, as the writers name them."""
    for table in TABLES:
        schema = declared_schema(table)
        row = pa.table({f.name: pa.array([None], f.type) for f in schema}, schema=schema)
        folder = root.table_dir(table)
        folder.mkdir(parents=True)
        for i in range(parts):
            pq.write_table(row, folder / f"k{i}--part-{i}.parquet")


def cpu_ms(repeat: int, fn: Callable[[], object]) -> float:
    fn()  # warm
    t0 = time.process_time()
    for _ in range(repeat):
        fn()
    return (time.process_time() - t0) / repeat * 1000


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = DataRoot.resolve(Path(tmp) / "data")
        write_parts(root, args.parts)
        wh = Warehouse(root)
        print(describe())
        print(f"{args.parts} parts per appended table, CPU ms per call, mean of {args.repeat}")
        print(f"connect {cpu_ms(args.repeat, lambda: wh.connect().close()):.0f}")
        print(f"user    {cpu_ms(args.repeat, lambda: wh.read_only_sql('SELECT 1')):.0f}")
        count = cpu_ms(args.repeat, lambda: wh.read_only_sql("SELECT count(*) FROM feedback"))
        print(f"count   {count:.0f}")


if __name__ == "__main__":
    main()
