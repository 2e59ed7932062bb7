"""Table attribution: counterfactual outcomes of collision runs (`evoeye explain`), append-only.

Layout: `<root>/warehouse/attribution/part-<utc stamp>-<id>.parquet`, columns as declared in
`schemas/warehouse/attribution.sql` (a derived table: `evoeye.store.derived`). A write
takes the warehouse writer lock, skips every (scenario_id, variant, software_version) already
stored and writes the rest as one new part, so re-running `explain` adds nothing and a killed
one resumes with the runs it had not written. Every connection sees the table as the view
`attribution`; the cause of a run is derived from it in `warehouse/views/`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import astuple, dataclass, fields

import pyarrow as pa

from evoeye.paths import DataRoot
from evoeye.store.catalog import write_catalog
from evoeye.store.derived import append_part, read_parts
from evoeye.store.lock import WriterLock
from evoeye.store.schema import declared_schema

ATTRIBUTION_TABLE = "attribution"


@dataclass(frozen=True)
class AttributionRow:
    """One counterfactual of one run (the table's columns before part_id and written_at)."""

    logical_scenario: str
    scenario_id: str
    software_version: str
    variant: str
    collided: bool
    collision_time_s: float | None
    min_distance_m: float | None
    struck_from_behind: bool | None

    @property
    def key(self) -> tuple[str, str, str]:
        return self.scenario_id, self.variant, self.software_version


def read_attribution(root: DataRoot,
                     software_version: str | None = None) -> pa.Table:
    """Rows of attribution (all, or one software version), ordered by run and variant."""
    return read_parts(root, ATTRIBUTION_TABLE, "attribution_rows", version=software_version)


def explained_keys(root: DataRoot,
                   software_version: str | None = None) -> set[tuple[str, str, str]]:
    """The (scenario_id, variant, software_version) triples already stored."""
    t = read_attribution(root, software_version)
    return set(zip(*(t.column(c).to_pylist() for c in
                     ("scenario_id", "variant", "software_version")), strict=True))


def write_attribution(root: DataRoot, rows: Sequence[AttributionRow],
                      *, refresh_catalog: bool = False) -> int:
    """Append the rows whose key is not stored yet, as one part; the number written. With
    `refresh_catalog`, rewrite the DuckDB catalog file so its `attribution` view sees them."""
    with WriterLock(root.writer_lock):
        done = explained_keys(root)
        new: dict[tuple[str, str, str], AttributionRow] = {}
        for r in rows:
            if r.key not in done:
                new.setdefault(r.key, r)
        if new:
            schema = declared_schema(ATTRIBUTION_TABLE)
            names = [f.name for f in fields(AttributionRow)]
            values = list(zip(*(astuple(r) for r in new.values()), strict=True))
            append_part(root, ATTRIBUTION_TABLE, {
                n: pa.array(v, schema.field(n).type) for n, v in zip(names, values, strict=True)
            })
        if refresh_catalog and root.duckdb_file.exists():
            write_catalog(root)
    return len(new)
