"""MCAP logs → warehouse: append every run not yet ingested; safe to re-run and safe to kill.

* Idempotent: the ledger is the committed `scenarios` rows (log path and scenario id); a log
  already there is skipped without being read.
* One conversion per log: a log the caller has converted already (`LoggedRun`, e.g. the
  campaign's, which scored it) is written from that conversion, not read again.
* Logs read side by side: with `workers` > 1, that many processes read and convert logs
  (`reading.py`: most of the cost) while this one writes parts in the logs' order; the
  warehouse's rows are the same with any number of workers.
* Crash-safe: a part's frames and frame_features are written before its scenarios rows (see
  `parts.py`); the views hide uncommitted parts, and the next ingest deletes them and ingests
  those runs again.
* Bad logs: a log that `read_run` rejects, whose metadata does not fit its logical scenario
  (`metadata.py`), or that cannot be a record, is moved to
  `<root>/quarantine/` with a `.reason.txt` beside it, and the rest is ingested.
* A run of a world variant (`evoeye.sim.worlds`, e.g. the follower) is left where it is and
  out of the warehouse, which has no column for the world: re-simulated from a `scenarios` row
  it would be another run. It is supervised from its log (`evoeye supervise` reads logs).
* Writers (`lock.py`): a full ingest holds the writer lock exclusively. An ingest of one batch
  folder (`batch=`, a campaign's) locks only its partition and its new runs' ids (a run id
  committed by another batch meanwhile is a duplicate, never committed twice), so campaigns
  ingest side by side; it leaves the DuckDB catalog file alone (`refresh_catalog`).
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future
from contextlib import closing
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import duckdb
import pyarrow as pa

from evoeye.log import LogError
from evoeye.paths import LOG_SUFFIX, DataRoot
from evoeye.sim.worlds import DEFAULT_WORLD
from evoeye.store.catalog import Warehouse, write_catalog
from evoeye.store.features import FEATURES, FrameFeatures
from evoeye.store.lock import WarehouseLockedError, WriterLock, key_lock
from evoeye.store.log_windows import LoggedRun
from evoeye.store.metadata import check_metadata
from evoeye.store.migrate import migrate
from evoeye.store.parts import PartStore
from evoeye.store.reading import read_logs
from evoeye.store.records import (
    RunRecordError,
    frame_features_table,
    scenario_row,
    scenarios_table,
    with_ingest_id,
)
from evoeye.store.schema import PARTITION_KEYS
from evoeye.store.windows import part_cache

DEFAULT_RUNS_PER_PART = 32
REASON_SUFFIX = ".reason.txt"


@dataclass
class IngestReport:
    """What one ingest did. Paths are relative to the data root."""

    ingested: list[str] = field(default_factory=list)  # scenario ids committed
    frames: int = 0  # frame rows committed
    skipped: int = 0  # logs already in the warehouse
    duplicates: list[str] = field(default_factory=list)  # logs of an already ingested scenario
    quarantined: list[tuple[str, str]] = field(default_factory=list)  # (log, reason)
    left_out: list[str] = field(default_factory=list)  # logs of a world variant (module doc)
    orphans_removed: list[str] = field(default_factory=list)  # parts of a killed ingest
    catalog_error: str | None = None  # the DuckDB file could not be refreshed (data is in)
    migrated: list[str] = field(default_factory=list)  # parts brought to LAYOUT_VERSION


def discover_logs(runs_dir: Path) -> list[Path]:
    """Every finished run log under `runs_dir`, sorted (`*.mcap.tmp` files are unfinished)."""
    if not runs_dir.is_dir():
        return []
    return sorted(p for p in runs_dir.rglob(f"*{LOG_SUFFIX}") if p.is_file())


class Quarantine:
    """Moves unreadable logs out of `runs/`, keeping their relative path, with the reason."""

    def __init__(self, root: DataRoot) -> None:
        self.root = root

    def move(self, log: Path, reason: str) -> Path:
        try:
            rel = Path(os.path.abspath(log)).relative_to(self.root.runs)
        except ValueError:
            rel = Path(log.name)
        dest = self.root.quarantine / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        log.replace(dest)
        dest.with_name(dest.name + REASON_SUFFIX).write_text(reason + "\n", encoding="utf-8")
        return dest


@dataclass
class _PendingPart:
    """Runs of one partition waiting to be written as one part."""

    part: str
    rows: list[dict] = field(default_factory=list)
    frames: list[pa.Table] = field(default_factory=list)
    features: list[pa.Table] = field(default_factory=list)  # frame_features, run by run
    converted: list[FrameFeatures | None] = field(default_factory=list)  # as computed, if


Partition = tuple[str, str]  # (logical scenario, batch)


class Ingester:
    """Ingests the logs under one data root; `run()` does one pass under the writer lock."""

    def __init__(
        self,
        root: DataRoot,
        *,
        runs_per_part: int = DEFAULT_RUNS_PER_PART,
        on_log: Callable[[Path], None] | None = None,
        on_start: Callable[[int], None] | None = None,
        batch: Partition | None = None,
        workers: int = 1,
    ) -> None:
        if runs_per_part < 1:
            raise ValueError(f"runs_per_part must be at least 1, got {runs_per_part}")
        self.root = root
        self.runs_per_part = runs_per_part
        self.on_log = on_log  # progress callback, called before each log is read
        self.on_start = on_start  # called once with the number of logs to read
        self.store = PartStore(self.root)
        self.quarantine = Quarantine(self.root)
        self.batch = batch  # only this batch's folder, as a writer of its keys (module doc)
        if workers < 1:
            raise ValueError(f"workers must be at least 1, got {workers}")
        self.workers = workers  # processes reading logs (`reading.py`); parts are written here

    def run(self, converted: Sequence[LoggedRun] = ()) -> IngestReport:
        """One pass; `converted`: runs of the logs to ingest already converted (by path)."""
        report = IngestReport()
        if self.batch is None:  # a whole-warehouse writer brings an old layout up first
            report.migrated = [self.root.relative(p) for p in migrate(self.root)]
        self.store.check_layout()  # never a part of this layout beside older ones
        given = {self.root.relative(c.path): c for c in converted}
        if self.batch is None:
            with WriterLock(self.root.writer_lock):
                report.orphans_removed = [self.root.relative(p)
                                          for p in self.store.remove_orphans()]
                ledger = Warehouse(self.root).query("committed_runs")
                self._ingest_new(discover_logs(self.root.runs), ledger, given, report)
                try:
                    write_catalog(self.root)
                except duckdb.Error as e:
                    report.catalog_error = f"{self.root.duckdb_file}: {e}"
            return report
        logs = discover_logs(self.root.batch_dir(*self.batch))
        # the batch's key and every run id it may write, taken in one sorted acquisition: two
        # keys can share a stripe, and a stripe taken twice by one process waits for itself
        keys = ["/".join(self.batch), *(log.name.removesuffix(LOG_SUFFIX) for log in logs)]
        with key_lock(self.root, "scenarios", keys):
            report.orphans_removed = [self.root.relative(p)
                                      for p in self.store.remove_orphans(self.batch)]
            mine = self.store.committed(self.batch)
            new = [log for log in logs if self.root.relative(log) not in mine]
            ids = [log.name.removesuffix(LOG_SUFFIX) for log in new]
            ledger = (Warehouse(self.root).query("committed_ids", ids=ids) if ids
                      else pa.table({"scenario_id": [], "log_path": []}))  # by another batch?
            report.skipped += len(logs) - len(new)
            self._ingest_new(new, ledger, given, report)
        return report

    def _ingest_new(self, logs: Sequence[Path], ledger: pa.Table, given: dict[str, LoggedRun],
                    report: IngestReport) -> None:
        """Ingest those of `logs` the ledger (committed scenario_id, log_path) has not."""
        done_paths = set(ledger.column("log_path").to_pylist())
        done_ids = set(ledger.column("scenario_id").to_pylist())
        pending = list(self._pending(logs, report, done_paths, done_ids))
        if self.on_start is not None:
            self.on_start(len(pending))
        self._ingest(pending, given, done_ids, report)

    def _pending(
        self, logs: Sequence[Path], report: IngestReport, done_paths: set[str], done_ids: set[str]
    ) -> Iterator[Path]:
        for log in logs:
            rel = self.root.relative(log)
            if rel in done_paths:
                report.skipped += 1
            elif log.name.removesuffix(LOG_SUFFIX) in done_ids:
                report.duplicates.append(rel)
            else:
                yield log

    def _ingest(self, logs: Sequence[Path], given: dict[str, LoggedRun], done_ids: set[str],
                report: IngestReport) -> None:
        reads = read_logs([log for log in logs if self.root.relative(log) not in given],
                          self.workers)
        with closing(reads):  # its pool stops however this loop ends
            self._write_runs(logs, reads, given, done_ids, report)

    def _write_runs(self, logs: Sequence[Path], reads: Iterator[tuple[Path, Future]],
                    given: dict[str, LoggedRun], done_ids: set[str], report: IngestReport) -> None:
        stamp = datetime.now(UTC)
        prefix = f"part-{stamp:%Y%m%dT%H%M%SZ}-{uuid.uuid4().hex[:8]}"
        counter = iter(range(1_000_000))
        pending: dict[tuple[str, str], _PendingPart] = {}
        for log in logs:
            if self.on_log is not None:
                self.on_log(log)
            rel = self.root.relative(log)
            converted = given.get(rel)
            try:
                if converted is None:
                    meta, read = next(reads)[1].result()  # raises what reading it raised
                else:
                    meta, read = converted.metadata, converted
                    check_metadata(meta)
                if read is None or meta.get("world", DEFAULT_WORLD) != DEFAULT_WORLD:
                    report.left_out.append(rel)
                    continue
                scenario_id = str(meta["scenario_id"])
                if scenario_id in done_ids:
                    report.duplicates.append(rel)
                    continue
                key = tuple(str(meta[k]) for k in PARTITION_KEYS)
                part = pending.get(key) or _PendingPart(f"{prefix}-{next(counter):04d}")
                frames = with_ingest_id(read.frames, part.part)
                features = frame_features_table(frames, features=read.features)
                row = scenario_row(
                    meta, n_frames=frames.num_rows, log_path=rel, ingest_id=part.part,
                    ingested_at=stamp,
                )
            except (LogError, RunRecordError) as e:
                self.quarantine.move(log, str(e))
                report.quarantined.append((rel, str(e)))
                continue
            done_ids.add(scenario_id)
            part.rows.append(row)
            part.frames.append(frames)
            part.features.append(features)
            part.converted.append(converted.features if converted else None)
            pending[key] = part
            if len(part.rows) >= self.runs_per_part:
                self._write(key, pending.pop(key), report)
        for key, part in pending.items():
            self._write(key, part, report)

    def _write(self, partition: Partition, part: _PendingPart, report: IngestReport) -> None:
        frames = pa.concat_tables(part.frames)
        self.store.write("frames", partition, part.part, frames)
        self.store.write("frame_features", partition, part.part, pa.concat_tables(part.features))
        cache = part_cache()
        if cache is not None and all(f is not None for f in part.converted):
            features = FrameFeatures.empty(frames.num_rows, FEATURES)
            start = 0
            for one in part.converted:
                features.fill(start, one)
                start += len(one)
            cache.put((partition, part.part), frames, features)  # never decoded here
        self.store.commit(partition, part.part, scenarios_table(part.rows))
        report.ingested += [r["scenario_id"] for r in part.rows]
        report.frames += frames.num_rows


def ingest(
    root: DataRoot,
    *,
    runs_per_part: int = DEFAULT_RUNS_PER_PART,
    on_log: Callable[[Path], None] | None = None,
    on_start: Callable[[int], None] | None = None,
    workers: int = 1,
) -> IngestReport:
    """Ingest every log under `<root>/runs` not yet in the warehouse (see the module doc);
    `on_start(n)` learns how many logs will be read, `on_log(path)` is called before each;
    `workers` processes read the logs (`evoeye.store.reading`), with the same result."""
    return Ingester(root, runs_per_part=runs_per_part, on_log=on_log, on_start=on_start,
                    workers=workers).run()


def ingest_batch(root: DataRoot, batch: Partition,
                 converted: Sequence[LoggedRun] = ()) -> IngestReport:
    """Ingest the logs of one batch folder not yet in the warehouse — those in `converted`
    from their conversion — as a writer of that batch's keys only (module doc)."""
    return Ingester(root, batch=batch).run(converted)


def refresh_catalog(root: DataRoot) -> None:
    """Rewrite the DuckDB catalog file's views (after batch ingests, which leave it alone), one
    writer of the file at a time; a no-op while a full writer holds the warehouse."""
    try:
        with key_lock(root, "catalog", ["catalog"]):
            write_catalog(root)
    except WarehouseLockedError:
        pass  # the full writer rewrites it when it finishes
