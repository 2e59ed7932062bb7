"""MCAP logs → warehouse: append every run not yet ingested; safe to re-run and safe to kill.

* Idempotent: the ledger is the committed `scenarios` rows (log path and scenario id); a log
  already there is skipped without being read.
* Crash-safe: a part's frames and frame_features are written before its scenarios rows (see
  `parts.py`); the views hide uncommitted parts, and the next ingest deletes them and ingests
  those runs again.
* Bad logs: a log that `read_run` rejects, whose metadata does not fit its logical scenario
  (`metadata.py`), or that cannot be a record, is moved to
  `<root>/quarantine/` with a `.reason.txt` beside it, and the rest is ingested.
* One writer: everything runs under the writer lock (`lock.py`).
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import duckdb
import pyarrow as pa

from evoeye.log import LogError, read_run
from evoeye.paths import LOG_SUFFIX, DataRoot
from evoeye.store.catalog import Warehouse, write_catalog
from evoeye.store.lock import WriterLock
from evoeye.store.metadata import check_metadata
from evoeye.store.parts import PartStore
from evoeye.store.records import (
    FRAME_CLOCK,
    RunRecordError,
    frame_column_sources,
    frame_features_table,
    frames_table,
    scenario_row,
    scenarios_table,
)
from evoeye.store.schema import PARTITION_KEYS

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
    orphans_removed: list[str] = field(default_factory=list)  # parts of a killed ingest
    catalog_error: str | None = None  # the DuckDB file could not be refreshed (data is in)


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


class Ingester:
    """Ingests the logs under one data root; `run()` does one pass under the writer lock."""

    def __init__(
        self,
        root: DataRoot,
        *,
        runs_per_part: int = DEFAULT_RUNS_PER_PART,
        on_log: Callable[[Path], None] | None = None,
        on_start: Callable[[int], None] | None = None,
    ) -> None:
        if runs_per_part < 1:
            raise ValueError(f"runs_per_part must be at least 1, got {runs_per_part}")
        self.root = root
        self.runs_per_part = runs_per_part
        self.on_log = on_log  # progress callback, called before each log is read
        self.on_start = on_start  # called once with the number of logs to read
        self.store = PartStore(self.root)
        self.quarantine = Quarantine(self.root)
        self.topics = sorted({FRAME_CLOCK, *(t for t, _ in frame_column_sources().values())})

    def run(self) -> IngestReport:
        report = IngestReport()
        with WriterLock(self.root.writer_lock):
            report.orphans_removed = [self.root.relative(p) for p in self.store.remove_orphans()]
            ledger = Warehouse(self.root).query("committed_runs")
            done_paths = set(ledger.column("log_path").to_pylist())
            done_ids = set(ledger.column("scenario_id").to_pylist())
            pending = list(self._pending(report, done_paths, done_ids))
            if self.on_start is not None:
                self.on_start(len(pending))
            self._ingest(iter(pending), done_ids, report)
            try:
                write_catalog(self.root)
            except duckdb.Error as e:
                report.catalog_error = f"{self.root.duckdb_file}: {e}"
        return report

    def _pending(
        self, report: IngestReport, done_paths: set[str], done_ids: set[str]
    ) -> Iterator[Path]:
        for log in discover_logs(self.root.runs):
            rel = self.root.relative(log)
            if rel in done_paths:
                report.skipped += 1
            elif log.name.removesuffix(LOG_SUFFIX) in done_ids:
                report.duplicates.append(rel)
            else:
                yield log

    def _ingest(self, logs: Iterator[Path], done_ids: set[str], report: IngestReport) -> None:
        stamp = datetime.now(UTC)
        prefix = f"part-{stamp:%Y%m%dT%H%M%SZ}-{uuid.uuid4().hex[:8]}"
        counter = iter(range(1_000_000))
        pending: dict[tuple[str, str], _PendingPart] = {}
        for log in logs:
            if self.on_log is not None:
                self.on_log(log)
            rel = self.root.relative(log)
            try:
                run = read_run(log, topics=self.topics)
                meta = run.metadata
                check_metadata(meta)
                scenario_id = str(meta["scenario_id"])
                if scenario_id in done_ids:
                    report.duplicates.append(rel)
                    continue
                key = tuple(str(meta[k]) for k in PARTITION_KEYS)
                part = pending.get(key) or _PendingPart(f"{prefix}-{next(counter):04d}")
                frames = frames_table(run, scenario_id, part.part)
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
            pending[key] = part
            if len(part.rows) >= self.runs_per_part:
                self._write(key, pending.pop(key), report)
        for key, part in pending.items():
            self._write(key, part, report)

    def _write(self, partition: tuple[str, str], part: _PendingPart, report: IngestReport) -> None:
        frames = pa.concat_tables(part.frames)
        self.store.write("frames", partition, part.part, frames)
        self.store.write("frame_features", partition, part.part, frame_features_table(frames))
        self.store.commit(partition, part.part, scenarios_table(part.rows))
        report.ingested += [r["scenario_id"] for r in part.rows]
        report.frames += frames.num_rows


def ingest(
    root: DataRoot,
    *,
    runs_per_part: int = DEFAULT_RUNS_PER_PART,
    on_log: Callable[[Path], None] | None = None,
    on_start: Callable[[int], None] | None = None,
) -> IngestReport:
    """Ingest every log under `<root>/runs` not yet in the warehouse (see the module doc);
    `on_start(n)` learns how many logs will be read, `on_log(path)` is called before each."""
    return Ingester(root, runs_per_part=runs_per_part, on_log=on_log, on_start=on_start).run()
