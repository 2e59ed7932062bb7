"""Bags into the warehouse: each converted whole, written as an evoeye run log, then ingested.

A bag becomes `runs/<logical scenario>/<batch>/<scenario id>.mcap` — an evoeye log like a
simulated run's (`evoeye.log.writer.write_run`), written atomically only once the whole bag has
converted — and the batch folder is ingested through the same path as simulated runs
(`evoeye.store.ingest.ingest_batch`). So a bag that fails is nowhere (not half-ingested), the
others go in, and a bag imported again is skipped: its run id is in the warehouse already.
The log is kept: `evoeye replay` replays it, and the warehouse can be rebuilt from `runs/`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from evoeye.log.writer import write_run
from evoeye.paths import DataRoot, check_batch_name
from evoeye.sources.autoware.bag import BagError, ImportedRun, bag_run_id, read_bag
from evoeye.sources.autoware.config import Mapping
from evoeye.store.ingest import IngestReport, ingest_batch, refresh_catalog

DEFAULT_BATCH = "autoware"


@dataclass
class ImportReport:
    """What an import did: one line per refused bag, the ingest of the batches written."""

    logs: list[Path] = field(default_factory=list)  # run logs written (or found) per bag
    failed: list[str] = field(default_factory=list)  # one line each: bag, topic, problem
    notes: list[str] = field(default_factory=list)
    labels: dict[str, str] = field(default_factory=dict)  # scenario id → label source, of
    # the bags converted this time (not those whose run log was there already)
    ingest: list[IngestReport] = field(default_factory=list)


def find_bags(paths: Sequence[Path]) -> list[Path]:
    """The bags named: a rosbag2 folder (with metadata.yaml), an .mcap or .db3 file, or a folder
    holding such bags (searched one level down)."""
    out: list[Path] = []
    for p in paths:
        if p.is_dir() and not (p / "metadata.yaml").exists():
            out += sorted(q for q in p.iterdir() if (q / "metadata.yaml").exists()
                          or q.suffix in (".mcap", ".db3"))
        else:
            out.append(p)
    return out


@dataclass(frozen=True)
class Recordings:
    """How one stack's recordings are found, identified and converted (Autoware's by default;
    Apollo's: `evoeye.sources.apollo.run.RECORDS`). Each raises BagError on one it refuses."""

    find: Callable[[Sequence[Path]], list[Path]] = find_bags
    run_id: Callable[[Path], tuple[str, str]] = bag_run_id  # (logical scenario, scenario id)
    read: Callable[..., ImportedRun] = read_bag  # (path, mapping) → the run


def import_bags(root: DataRoot, paths: Sequence[Path], *, mapping: Mapping | None = None,
                batch: str = DEFAULT_BATCH,
                on_bag: Callable[[Path], None] | None = None,
                recordings: Recordings | None = None) -> ImportReport:
    """Convert every recording of `paths`, write its run log, and ingest the batches
    written."""
    recordings = recordings or Recordings()
    check_batch_name(batch)
    report = ImportReport()
    partitions: set[tuple[str, str]] = set()
    bag_of: dict[str, Path] = {}  # run log (relative to the root) → its bag
    for bag in recordings.find(paths):
        if on_bag is not None:
            on_bag(bag)
        try:
            scenario, sid = recordings.run_id(bag)
            log = root.run_log(scenario, batch, sid)
            if not log.exists():  # converted before: its log is the run
                run = recordings.read(bag, mapping)
                log.parent.mkdir(parents=True, exist_ok=True)
                write_run(dict(run.metadata, batch=batch), run.messages(), log)
                report.notes += run.notes
                report.labels[sid] = run.metadata["label_source"]
        except BagError as e:
            report.failed.append(str(e))
            continue
        report.logs.append(log)
        bag_of[root.relative(log)] = bag
        partitions.add((scenario, batch))
    for partition in sorted(partitions):
        ingested = ingest_batch(root, partition)
        report.ingest.append(ingested)
        for log, reason in ingested.quarantined:  # the log is moved aside: nothing went in
            report.failed.append(f"{bag_of.get(log, log)}: (bag): not ingested ({reason})")
    if partitions:
        refresh_catalog(root)  # a batch ingest leaves the DuckDB file's views alone
    return report
