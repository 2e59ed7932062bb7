"""Warehouse layouts that can be brought to LAYOUT_VERSION in place, part by part.

A migration rewrites every part of the ingested tables whose layout is in `MIGRATABLE`: each
part is read, cast to the declared schema of today (the DDL) and written under the same name,
atomically, stamped with LAYOUT_VERSION (`PartStore.write`). A killed migration leaves every
part either as it was or migrated, and the next one finishes the rest; the views refuse a
warehouse of mixed layouts until it has. Older layouts change more than column types and are
re-ingested from their logs instead (docs/warehouse.md, "Warehouse layouts").

Layout 4 → 5: the actor ids `scenarios.other_actor` and `frames.gt_collision_actor` widen from
INTEGER to BIGINT (another stack's object UUIDs are 64-bit ids, docs/autoware.md).
"""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq

from evoeye.paths import DataRoot
from evoeye.store.lock import WriterLock
from evoeye.store.parts import PART_SUFFIX, PartStore, part_layout
from evoeye.store.schema import MIGRATABLE, PARTITION_KEYS, TABLES, file_schema


def _partition(path: Path) -> tuple[str, str]:
    """(logical scenario, batch) of a part from its hive folders."""
    folders = path.parts[-1 - len(PARTITION_KEYS):-1]
    return tuple(f.split("=", 1)[1] for f in folders)  # type: ignore[return-value]


def parts_to_migrate(root: DataRoot) -> list[tuple[str, Path]]:
    """(table, part) of every ingested part of a migratable layout."""
    glob = "/".join(["*"] * len(PARTITION_KEYS)) + f"/*{PART_SUFFIX}"
    return [(table, part) for table in TABLES
            for part in sorted(root.table_dir(table).glob(glob))
            if part_layout(pq.read_schema(part).metadata) in MIGRATABLE]


def migrate(root: DataRoot) -> list[Path]:
    """Rewrite every part of a migratable layout as LAYOUT_VERSION, under the writer lock;
    the parts rewritten. Parts of other layouts are left alone (the layout check names them)."""
    if not parts_to_migrate(root):
        return []
    store, done = PartStore(root), []
    with WriterLock(root.writer_lock):
        for table, part in parts_to_migrate(root):  # again, under the lock
            data = pq.read_table(part, partitioning=None)
            data = data.cast(file_schema(table).with_metadata(data.schema.metadata))
            store.write(table, _partition(part), part.name.removesuffix(PART_SUFFIX), data)
            done.append(part)
    return done

