"""The warehouse: MCAP logs → Parquet tables with DuckDB views; labels and windows in SQL.

Writers: `ingest` (one at a time, under the writer lock). Readers: `Warehouse` (SQL over the
Parquet), `load_windows` (labelled contexts as numpy / torch), `select_runs` (subsets, splits).
"""

from evoeye.store.catalog import Warehouse
from evoeye.store.features import FEATURES, FeatureSpec, FrameFeatures, frame_features
from evoeye.store.ingest import IngestReport, ingest
from evoeye.store.lock import WarehouseLockedError, WriterLock
from evoeye.store.selection import SPLITS, RunFilter, SplitSpec, select_runs
from evoeye.store.windows import WindowBatch, Windows, load_windows

__all__ = [
    "FEATURES",
    "SPLITS",
    "FeatureSpec",
    "FrameFeatures",
    "IngestReport",
    "RunFilter",
    "SplitSpec",
    "Warehouse",
    "WarehouseLockedError",
    "WindowBatch",
    "Windows",
    "WriterLock",
    "frame_features",
    "ingest",
    "load_windows",
    "select_runs",
]
