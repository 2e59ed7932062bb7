"""The Parquet parts of the warehouse tables: atomic writes, commit order, orphan clean-up.

A part is one Parquet file per table per partition, named `<ingest_id>.parquet`, holding the
rows of one or more runs. The `frames` and `frame_features` parts are written first; writing
the `scenarios` part of the same name commits its runs. Each write goes to a temporary file
that is fsynced and renamed, so a file under a final name is always complete; a part without
its `scenarios` twin is an orphan of a killed ingest, invisible to the views (they join on
ingest_id) and removed by the next writer.
"""

from __future__ import annotations

import os
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.atomic import atomic_file, fsync_dir
from evoeye.paths import DataRoot
from evoeye.store.schema import (
    LAYOUT_KEY,
    LAYOUT_VERSION,
    MIGRATABLE,
    PARTITION_KEYS,
    TABLES,
    WarehouseLayoutError,
    canonical_schema,
    file_schema,
)

PART_SUFFIX = ".parquet"
TMP_SUFFIX = ".tmp"
# Raw tables are cold storage: zstd. frame_features is read whole for every training set, so
# it trades disk for read speed (see benchmarks/bench_warehouse.py).
COMPRESSION = {"scenarios": "zstd", "frames": "zstd", "frame_features": "lz4"}


def _write_options(table: str, schema: pa.Schema) -> dict:
    """Dictionaries for string columns only, statistics for scalar columns only: float
    arrays (lists, or float32 bytes) neither repeat nor get filtered on, and both would slow
    writes and reads."""
    scalar = [f.name for f in schema
              if not (pa.types.is_list(f.type) or pa.types.is_fixed_size_binary(f.type))]
    strings = [f.name for f in schema if f.type in (pa.string(), pa.list_(pa.string()))]
    return {
        "compression": COMPRESSION[table],
        "use_dictionary": strings,
        "write_statistics": scalar,
    }


def part_layout(metadata: dict[bytes, bytes] | None) -> int:
    """The layout version a part's Parquet (schema) metadata names; 1 if none (written before
    parts named theirs)."""
    return int((metadata or {}).get(LAYOUT_KEY, b"1"))


def check_part_layout(path: Path, metadata: dict[bytes, bytes] | None = None) -> None:
    """WarehouseLayoutError naming the part, its layout and the fix, unless it is of
    LAYOUT_VERSION; `metadata`: its schema metadata, if read already."""
    found = part_layout(pq.read_schema(path).metadata if metadata is None else metadata)
    if found != LAYOUT_VERSION:
        warehouse = path.parents[len(PARTITION_KEYS) + 1]  # <root>/warehouse
        if found in MIGRATABLE:  # evoeye.store.migrate
            raise WarehouseLayoutError(
                f"{path}: a warehouse part of layout {found}; this evoeye reads layout "
                f"{LAYOUT_VERSION} only (docs/warehouse.md, Warehouse layouts) — migrate: run "
                f"`evoeye ingest` on the data root of {warehouse} once (it rewrites the parts "
                "in place)")
        raise WarehouseLayoutError(
            f"{path}: a warehouse part of layout {found}; this evoeye reads layout "
            f"{LAYOUT_VERSION} only (docs/warehouse.md, Warehouse layouts) — re-ingest: move "
            f"the folders {', '.join(t for t in TABLES)} out of {warehouse} and run "
            "`evoeye ingest` on the data root again (its logs under runs/ are the source)")


class PartStore:
    """Writes and lists the Parquet parts of `scenarios` and `frames` under one data root."""

    def __init__(self, root: DataRoot) -> None:
        self.root = root

    def partition_dir(self, table: str, partition: tuple[str, str]) -> Path:
        folders = [f"{k}={v}" for k, v in zip(PARTITION_KEYS, partition, strict=True)]
        return self.root.table_dir(table).joinpath(*folders)

    def write(self, table: str, partition: tuple[str, str], part: str, data: pa.Table) -> Path:
        """Write `data` as part `part` of `table`, atomically; the final path."""
        expected = canonical_schema(file_schema(table))
        if canonical_schema(data.schema) != expected:
            raise ValueError(f"{table} part does not match the DDL:\n{data.schema}")
        folder = self.partition_dir(table, partition)
        folder.mkdir(parents=True, exist_ok=True)
        final = folder / f"{part}{PART_SUFFIX}"
        tmp = folder / f".{part}{PART_SUFFIX}.{os.getpid()}{TMP_SUFFIX}"
        stamped = data.replace_schema_metadata(
            {**(data.schema.metadata or {}), LAYOUT_KEY: str(LAYOUT_VERSION).encode()})
        with atomic_file(final, tmp) as f:
            pq.write_table(stamped, f, **_write_options(table, data.schema))
        fsync_dir(folder)
        return final

    def commit(self, partition: tuple[str, str], part: str, scenarios: pa.Table) -> Path:
        """Write the scenarios part: from here on the part's runs are visible."""
        return self.write("scenarios", partition, part, scenarios)

    @staticmethod
    def _folders(partition: tuple[str, str] | None) -> str:
        """The partition folders under a table folder, as a glob: one partition's, or all."""
        if partition is None:
            return "/".join(["*"] * len(PARTITION_KEYS))
        return "/".join(f"{k}={v}" for k, v in zip(PARTITION_KEYS, partition, strict=True))

    def _parts(self, table: str, partition: tuple[str, str] | None) -> dict[Path, Path]:
        """Part path relative to the table folder → absolute path (of one partition, or all)."""
        base = self.root.table_dir(table)
        return {p.relative_to(base): p
                for p in base.glob(f"{self._folders(partition)}/*{PART_SUFFIX}")}

    def orphans(self, partition: tuple[str, str] | None = None) -> list[Path]:
        """Parts without a committed scenarios twin, and leftover temporary files (of one
        partition, or all)."""
        committed = set(self._parts("scenarios", partition))
        found: list[Path] = []
        for table in TABLES:
            if table != "scenarios":
                found += [p for rel, p in self._parts(table, partition).items()
                          if rel not in committed]
            found += self.root.table_dir(table).glob(
                f"{self._folders(partition)}/.*{TMP_SUFFIX}")
        return sorted(found)

    def committed(self, partition: tuple[str, str]) -> set[str]:
        """The log paths (relative to the root) of the runs committed in one partition."""
        return {path for part in self._parts("scenarios", partition).values()
                for path in pq.read_table(part, columns=["log_path"], partitioning=None)
                .column("log_path").to_pylist()}

    def check_layout(self) -> None:
        """WarehouseLayoutError if the ingested tables hold parts of another layout than
        LAYOUT_VERSION. One part per table is read: every writer checks before it adds one."""
        for table in TABLES:
            part = next(self.root.table_dir(table).glob(f"{self._folders(None)}/*{PART_SUFFIX}"),
                        None)
            if part is not None:
                check_part_layout(part)

    def remove_orphans(self, partition: tuple[str, str] | None = None) -> list[Path]:
        """Delete what `orphans` lists; call only under a lock on what it covers (the writer
        lock, or the partition's key)."""
        removed = self.orphans(partition)
        for path in removed:
            path.unlink(missing_ok=True)
        return removed
