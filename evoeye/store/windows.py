"""Training windows: runtime contexts c_t (Definition 2) with labels y_t (Definition 1).

`warehouse/queries/windows.sql` lists every eligible frame of the selected runs (none at or
after a run's collision: view eligible_frames) in (scenario_id, frame) order, with its label, the
ego's localization estimate and the row of its monitor inputs in the runs' frame_features parts;
the L context frames follow from that order (`context_rows`). The inputs are decoded by Arrow
straight from those Parquet parts into numpy (DuckDB never turns their float lists into rows of
its own) and kept once per frame: a window is `features[context]`, gathered when asked for (all
at once, or per training batch), so N frames cost N feature rows, not N·L.

Inside `cached_parts()`, every part decoded is kept (a part is written once and never changed):
a process that loads windows again and again — a campaign, whose training set grows by a
round's runs and whose validation split never changes — decodes each part once, and a part it
ingested from its own conversion (`evoeye.store.ingest`) never. The windows are the same, in the
same layout, with the cache or without.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING

import duckdb
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.paths import DataRoot
from evoeye.store.catalog import Warehouse
from evoeye.store.features import FEATURES, STORED_COLUMNS, FeatureSpec, FrameFeatures, unpack
from evoeye.store.parts import PART_SUFFIX, PartStore
from evoeye.store.selection import Runs, select_runs
from evoeye.store.sqlfiles import query

if TYPE_CHECKING:  # torch is imported when tensors are asked for, not by the SQL-only CLI
    import torch

DEFAULT_CONTEXT_LEN = 5  # L, paper §V "Implementation Settings"
DEFAULT_HORIZON_S = 3.0  # H


@dataclass
class WindowBatch:
    """Torch tensors of b windows; the feature tensors carry a context axis L after b."""

    perception: torch.Tensor  # (b, L, n, 9)
    perception_mask: torch.Tensor  # (b, L, n) bool
    prediction: torch.Tensor  # (b, L, n, K, 2)
    prediction_mask: torch.Tensor  # (b, L, n) bool
    plan: torch.Tensor  # (b, L, P, 7)
    plan_mask: torch.Tensor  # (b, L, P) bool
    plan_info: torch.Tensor  # (b, L, 6)
    control: torch.Tensor  # (b, L, 6)
    context_mask: torch.Tensor  # (b, L) bool, False on padded slots before the run start
    label: torch.Tensor  # (b,) float32 in {0, 1}

    def tensors(self) -> dict[str, torch.Tensor]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass
class Windows:
    """B labelled windows over N frames (here B = N: one window ends at every frame)."""

    features: FrameFeatures  # (N, …) per frame, in no particular order
    context: np.ndarray  # (B, L) int64 rows of `features`, oldest first
    context_mask: np.ndarray  # (B, L) bool
    label: np.ndarray  # (B,) int8, y_t for `horizon_s`
    scenario_id: np.ndarray  # (B,) object (str)
    frame: np.ndarray  # (B,) int32, t (0-based) within its run
    t_s: np.ndarray  # (B,) float64
    horizon_s: float
    spec: FeatureSpec
    ego_xy_m: np.ndarray | None = None  # (B, 2) float64, localization x, y (map frame) at t

    def __len__(self) -> int:
        return int(self.label.shape[0])

    @property
    def context_len(self) -> int:
        return int(self.context.shape[1])

    def arrays(self, index: np.ndarray | slice | None = None) -> dict[str, np.ndarray]:
        """The windows `index` (default all) as numpy arrays (b, L, …), gathered in one step."""
        sel = slice(None) if index is None else index
        rows = self.context[sel]  # (b, L)
        out = {name: np.take(arr, rows, axis=0) for name, arr in self.features.arrays().items()}
        out["context_mask"] = self.context_mask[sel]
        out["label"] = self.label[sel].astype(np.float32)
        return out

    def batch(self, index: np.ndarray | slice | None = None) -> WindowBatch:
        """The windows `index` (default all) as torch tensors (b, L, …)."""
        import torch

        return WindowBatch(**{k: torch.from_numpy(v) for k, v in self.arrays(index).items()})

    def subset(self, index: np.ndarray | slice) -> Windows:
        """Some of the windows, sharing the frame features (e.g. one scenario, a stride)."""
        return Windows(
            self.features, self.context[index], self.context_mask[index], self.label[index],
            self.scenario_id[index], self.frame[index], self.t_s[index], self.horizon_s,
            self.spec, None if self.ego_xy_m is None else self.ego_xy_m[index],
        )


FEATURE_KEYS = ("scenario_id", "frame", "ingest_id")  # what windows.sql matches feature_rows on


class PartCache:
    """frame_features parts decoded by this process, by path: their keys and their features."""

    def __init__(self) -> None:
        self._keys: dict[Path, pa.Table] = {}
        self._features: dict[Path, FrameFeatures] = {}

    def put(self, path: Path, keys: pa.Table, features: FrameFeatures | None = None) -> None:
        """Keep a part's key columns (FEATURE_KEYS) and, if given, its features (every row)."""
        self._keys[Path(path)] = _plain_keys(keys)
        if features is not None:
            self._features[Path(path)] = features

    def keys(self, path: Path) -> pa.Table:
        if path not in self._keys:
            self._keys[path] = _read_keys(path)
        return self._keys[path]

    def features(self, path: Path) -> FrameFeatures:
        if path not in self._features:
            self._features[path] = _decode(path)
        return self._features[path]


_CACHE: ContextVar[PartCache | None] = ContextVar("evoeye_part_cache", default=None)


@contextmanager
def cached_parts() -> Iterator[PartCache]:
    """Within the block, every frame_features part is decoded once (module doc)."""
    token = _CACHE.set(PartCache())
    try:
        yield _CACHE.get()
    finally:
        _CACHE.reset(token)


def part_cache() -> PartCache | None:
    """The cache of the enclosing `cached_parts()` block, if any."""
    return _CACHE.get()


def _decode(path: Path) -> FrameFeatures:
    """Every row of a frame_features part."""
    part = pq.read_table(path, columns=list(STORED_COLUMNS), partitioning=None)
    out = FrameFeatures.empty(part.num_rows, FEATURES)
    start = 0
    for batch in part.to_batches():
        out.fill(start, unpack(batch, FEATURES))
        start += batch.num_rows
    return out


def _plain_keys(table: pa.Table) -> pa.Table:
    """The FEATURE_KEYS columns of a table, with plain fields (as every part's concatenate)."""
    return pa.table({name: table.column(name) for name in FEATURE_KEYS})


def _read_keys(path: Path) -> pa.Table:
    return _plain_keys(pq.read_table(path, columns=list(FEATURE_KEYS), partitioning=None))


def context_rows(run_start: np.ndarray, context_len: int) -> tuple[np.ndarray, np.ndarray]:
    """(ctx_row, ctx_mask), both (B, L), of B rows in run order, row i of the run starting at
    row run_start[i]: rows i-L+1 … i oldest first, clamped to the run's first row, and masked
    exactly where clamped (Definition 2: c_t = (m_max(1,t-L+1), …, m_t) read element-wise)."""
    back = np.arange(len(run_start))[:, None] - run_start[:, None] - context_len + 1 \
        + np.arange(context_len)[None, :]  # (B, L) position in the run, negative before it
    return run_start[:, None] + np.maximum(back, 0), back >= 0


def _part_paths(con: duckdb.DuckDBPyConnection, root: DataRoot) -> list[Path]:
    """The frame_features part files holding the runs in `selected_runs` (query window_parts)
    that exist (a run whose part is missing gets no feature rows, and load_windows says so)."""
    store = PartStore(root)
    paths = [store.partition_dir("frame_features", (ls, batch)) / f"{part}{PART_SUFFIX}"
             for ls, batch, part in con.sql(query("window_parts")).fetchall()]
    return [path for path in paths if path.is_file()]


def _feature_rows(paths: list[Path]) -> pa.Table:
    """The keys of the rows of `paths`, in file order, numbered: relation `feature_rows`."""
    cache = part_cache()
    keys = [cache.keys(path) if cache else _read_keys(path) for path in paths]
    table = pa.concat_tables(keys) if keys else pa.table(
        {"scenario_id": pa.array([], pa.string()), "frame": pa.array([], pa.int32()),
         "ingest_id": pa.array([], pa.string())})
    return table.append_column("feature_row", pa.array(np.arange(table.num_rows)))


def _gather_features(paths: list[Path], source: np.ndarray, spec: FeatureSpec
                     ) -> tuple[FrameFeatures, np.ndarray]:
    """The feature rows `source` (positions in the concatenated rows of `paths`, as numbered by
    `_feature_rows`) in one FrameFeatures, and where each entry of `source` went.

    Arrow decodes one part at a time straight from Parquet (DuckDB never materialises the float
    lists); the rows used are copied once, in file order, and the part is freed."""
    order = np.argsort(source, kind="stable")
    sorted_source = source[order]
    features = FrameFeatures.empty(len(source), spec)
    cache = part_cache() if spec == FEATURES else None  # it holds the warehouse's spec
    offset = 0
    for path in paths:
        if cache is not None:
            part_features = cache.features(path)
            lo, hi = np.searchsorted(sorted_source, [offset, offset + len(part_features)])
            features.fill(int(lo), part_features, sorted_source[lo:hi] - offset)
            offset += len(part_features)
            continue
        part = pq.read_table(path, columns=list(STORED_COLUMNS), partitioning=None)
        lo, hi = np.searchsorted(sorted_source, [offset, offset + part.num_rows])
        if hi > lo:
            rows = sorted_source[lo:hi] - offset
            start = int(lo)
            for batch in part.to_batches():
                take = rows[(rows >= 0) & (rows < batch.num_rows)]
                if len(take):
                    features.fill(start, unpack(batch, spec), take)
                    start += len(take)
                rows = rows - batch.num_rows
        offset += part.num_rows
    position = np.empty(len(source), np.int64)
    position[order] = np.arange(len(source))
    return features, position


def _runs(col: pa.ChunkedArray) -> tuple[np.ndarray, np.ndarray]:
    """A scenario_id column grouped by run → (object array, one Python str per run; (B,) the
    first row of each row's run)."""
    encoded = col.combine_chunks().dictionary_encode()
    names = np.array(encoded.dictionary.to_pylist(), dtype=object)
    code = encoded.indices.to_numpy(zero_copy_only=False)
    new_run = np.ones(len(code), bool)
    new_run[1:] = code[1:] != code[:-1]
    starts = np.flatnonzero(new_run)
    return names[code], np.repeat(starts, np.diff(np.append(starts, len(code))))


def load_windows(
    root: Warehouse | DataRoot,
    runs: Runs = None,
    *,
    context_len: int = DEFAULT_CONTEXT_LEN,
    horizon_s: float = DEFAULT_HORIZON_S,
) -> Windows:
    """Every window of the selected runs (default: all runs with status 'ok'), labelled for H,
    one per eligible frame: no frame at or after a run's collision.

    `runs` is a RunFilter, a list of scenario ids or a SQL query returning scenario_id (see
    `select_runs`). Windows come in (scenario_id, frame) order.
    """
    if context_len < 1:
        raise ValueError(f"context length L must be at least 1, got {context_len}")
    if horizon_s <= 0:
        raise ValueError(f"horizon H must be positive, got {horizon_s}")
    warehouse = root if isinstance(root, Warehouse) else Warehouse(root)
    con = warehouse.connect()
    try:
        con.register("selected_runs", select_runs(con, runs))
        paths = _part_paths(con, warehouse.root)
        con.register("feature_rows", _feature_rows(paths))
        rows = con.sql(query("windows"), params={"horizon_s": float(horizon_s)}).to_arrow_table()
    finally:
        con.close()
    missing = rows.column("feature_row").null_count
    if missing:
        raise RuntimeError(f"{missing} frames of the selected runs have no frame_features")
    features, position = _gather_features(paths, rows.column("feature_row").to_numpy(), FEATURES)
    scenario_id, run_start = _runs(rows.column("scenario_id"))
    ctx_row, ctx_mask = context_rows(run_start, context_len)
    ego_xy_m = np.stack([rows.column(c).to_numpy(zero_copy_only=False).astype(np.float64)
                         for c in ("loc_x_m", "loc_y_m")], axis=1)
    return Windows(
        features, position[ctx_row], ctx_mask, rows.column("label").to_numpy().astype(np.int8),
        scenario_id, rows.column("frame").to_numpy().astype(np.int32),
        rows.column("t_s").to_numpy(), horizon_s, FEATURES, ego_xy_m,
    )
