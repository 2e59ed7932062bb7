"""Training windows: runtime contexts c_t (Definition 2) with labels y_t (Definition 1).

DuckDB answers which runs (`select_runs`) and which committed part holds each
(`warehouse/queries/window_runs.sql`, in scenario_id order: the order of the windows). Arrow
then reads each part: from its frames file the few columns a window needs (WINDOW_COLUMNS),
from its frame_features file the monitor inputs, float32 bytes numpy views without a copy (the
two files hold the same rows in the same order). Eligible frames (none at or after a run's
collision) and labels follow the views' definitions in numpy (`evoeye.store.labels`), and each
eligible frame's inputs are copied once, in window order; the L context frames follow from that
order (`context_rows`). A window is `features[context]`, gathered when asked for (all at once,
or per training batch), so N frames cost N feature rows, not N·L. Parts are read two at a time.

Inside `cached_parts()`, every part read is kept (a part is written once and never changed):
a process that loads windows again and again — a campaign, whose training set grows by a
round's runs and whose validation split never changes — decodes each part once, and a part it
ingested from its own conversion (`evoeye.store.ingest`) never. The windows are the same, in the
same layout, with the cache or without.
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from evoeye.paths import DataRoot
from evoeye.store.catalog import Warehouse
from evoeye.store.features import (
    FEATURES,
    MIN_SLICE_ROWS,
    STORED_COLUMNS,
    FeatureSpec,
    FrameFeatures,
    unpack,
)
from evoeye.store.labels import eligible_frames, frame_labels
from evoeye.store.parts import PART_SUFFIX, PartStore, check_part_layout
from evoeye.store.schema import file_schema
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

    def distinct_frames(self, index: np.ndarray | slice | None = None
                        ) -> tuple[np.ndarray, np.ndarray]:
        """(rows, inverse) of the windows `index`: the (U,) sorted distinct rows of `features`
        their contexts read, and the (b, L) position of each context slot among them — so a
        model can encode each frame once however many windows share it."""
        context = self.context[slice(None) if index is None else index]  # (b, L)
        rows, inverse = np.unique(context, return_inverse=True)
        return rows, inverse.reshape(context.shape)

    def batch(self, index: np.ndarray | slice | None = None) -> WindowBatch:
        """The windows `index` (default all) as torch tensors (b, L, …)."""
        import torch

        return WindowBatch(**{k: torch.from_numpy(v) for k, v in self.arrays(index).items()})

    def run_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(R,) each run's first window and (R,) one past its last (a run's windows are
        consecutive); both empty without windows."""
        sid = self.scenario_id
        starts = np.flatnonzero(np.r_[True, sid[1:] != sid[:-1]])[: len(sid)]
        return starts, np.r_[starts[1:], len(sid)][: len(starts)]

    def subset(self, index: np.ndarray | slice) -> Windows:
        """Some of the windows, sharing the frame features (e.g. one scenario, a stride)."""
        return Windows(
            self.features, self.context[index], self.context_mask[index], self.label[index],
            self.scenario_id[index], self.frame[index], self.t_s[index], self.horizon_s,
            self.spec, None if self.ego_xy_m is None else self.ego_xy_m[index],
        )


WINDOW_COLUMNS = ("scenario_id", "frame", "t_s", "gt_ego_collision", "loc_x_m", "loc_y_m")
Part = tuple[tuple[str, str], str]  # ((logical scenario, batch), ingest_id): a part's name
READERS = 2  # parts read at once (Arrow's reads and numpy's copies release the GIL)


@dataclass(frozen=True)
class PartRows:
    """The WINDOW_COLUMNS of a frames part, row by row (runs as indices into `names`)."""

    names: np.ndarray  # (R,) object: the part's scenario ids
    run: np.ndarray  # (n,) int32 index into names
    frame: np.ndarray  # (n,) int32
    t_s: np.ndarray  # (n,) float64
    collided: np.ndarray  # (n,) bool, gt_ego_collision
    ego_xy_m: np.ndarray  # (n, 2) float64, localization x, y (map frame)

    @classmethod
    def empty(cls) -> PartRows:
        return cls.of(pa.table({c: pa.array([], file_schema("frames").field(c).type)
                                for c in WINDOW_COLUMNS}))

    @classmethod
    def of(cls, table: pa.Table) -> PartRows:
        runs = table.column("scenario_id").combine_chunks()
        if not pa.types.is_dictionary(runs.type):
            runs = runs.dictionary_encode()
        return cls(
            np.array(runs.dictionary.to_pylist(), dtype=object),
            runs.indices.to_numpy(zero_copy_only=False).astype(np.int32),
            table.column("frame").to_numpy().astype(np.int32),
            table.column("t_s").to_numpy(),
            table.column("gt_ego_collision").to_numpy(zero_copy_only=False).astype(bool),
            np.stack([table.column(c).to_numpy(zero_copy_only=False).astype(np.float64)
                      for c in ("loc_x_m", "loc_y_m")], axis=1).reshape(-1, 2),
        )


def _read_rows(path: Path) -> PartRows:
    """A frames part's WINDOW_COLUMNS; none if the part is missing (as the views read it)."""
    if not path.is_file():
        return PartRows.empty()
    with pq.ParquetFile(path, memory_map=True, read_dictionary=["scenario_id"]) as part:
        return PartRows.of(part.read(columns=list(WINDOW_COLUMNS), use_threads=False))


def _read_features(path: Path) -> tuple[FrameFeatures, np.ndarray]:
    """Every row of a frame_features part (views of Arrow's buffers), and its frame column."""
    with pq.ParquetFile(path, memory_map=True) as file:  # a third less CPU than read_table
        check_part_layout(path, file.schema_arrow.metadata)
        part = file.read(columns=[*STORED_COLUMNS, "frame"], use_threads=False)
    return unpack(part, FEATURES), part.column("frame").to_numpy()


def _decode(path: Path) -> tuple[FrameFeatures, np.ndarray]:
    """A frame_features part read for `cached_parts()`."""
    return _read_features(path)


class PartCache:
    """Parts read by this process, by name: their frames' WINDOW_COLUMNS and their features."""

    def __init__(self) -> None:
        self._rows: dict[Part, PartRows] = {}
        self._features: dict[Part, tuple[FrameFeatures, np.ndarray]] = {}

    def put(self, part: Part, frames: pa.Table, features: FrameFeatures | None = None) -> None:
        """Keep a part's frames (their WINDOW_COLUMNS) and, if given, its features."""
        self._rows[part] = PartRows.of(frames.select(list(WINDOW_COLUMNS)))
        if features is not None:
            self._features[part] = (features, self._rows[part].frame)

    def rows(self, part: Part, path: Path) -> PartRows:
        if part not in self._rows:
            self._rows[part] = _read_rows(path)
        return self._rows[part]

    def has_features(self, part: Part) -> bool:
        return part in self._features

    def features(self, part: Part, path: Path) -> tuple[FrameFeatures, np.ndarray]:
        if part not in self._features:
            self._features[part] = _decode(path)
        return self._features[part]


_CACHE: ContextVar[PartCache | None] = ContextVar("evoeye_part_cache", default=None)


@contextmanager
def cached_parts() -> Iterator[PartCache]:
    """Within the block, every part is read once (module doc)."""
    token = _CACHE.set(PartCache())
    try:
        yield _CACHE.get()
    finally:
        _CACHE.reset(token)


def part_cache() -> PartCache | None:
    """The cache of the enclosing `cached_parts()` block, if any."""
    return _CACHE.get()


def context_rows(run_start: np.ndarray, context_len: int) -> tuple[np.ndarray, np.ndarray]:
    """(ctx_row, ctx_mask), both (B, L), of B rows in run order, row i of the run starting at
    row run_start[i]: rows i-L+1 … i oldest first, clamped to the run's first row, and masked
    exactly where clamped (Definition 2: c_t = (m_max(1,t-L+1), …, m_t) read element-wise)."""
    back = (np.arange(len(run_start)) - run_start)[:, None] \
        + np.arange(1 - context_len, 1)[None, :]  # (B, L) position in the run, < 0 before it
    mask = back >= 0
    np.maximum(back, 0, out=back)
    back += run_start[:, None]
    return back, mask


def _scatter(out: FrameFeatures, dst: np.ndarray, part: FrameFeatures, src: np.ndarray) -> None:
    """out[dst] = part[src] for every array: slice copies over the stretches where both step
    by one (a run's frames), one gather where the rows are scattered."""
    if len(src) == 0:
        return
    breaks = np.flatnonzero((np.diff(src) != 1) | (np.diff(dst) != 1)) + 1
    pairs = [(arr, getattr(out, name)) for name, arr in part.arrays().items()]
    if len(breaks) > len(src) // MIN_SLICE_ROWS:
        for arr, target in pairs:
            target[dst] = arr[src]
        return
    for lo, hi in zip(np.r_[0, breaks], np.r_[breaks, len(src)], strict=True):
        s, d, n = int(src[lo]), int(dst[lo]), int(hi - lo)
        for arr, target in pairs:
            target[d : d + n] = arr[s : s + n]


@dataclass(frozen=True)
class _Selected:
    """The eligible rows of the selected runs, in window order, and where each one sits."""

    part: np.ndarray  # (B,) index of the row's part
    row: np.ndarray  # (B,) its row in that part
    run: np.ndarray  # (B,) rank of its run in scenario_id order
    frame: np.ndarray  # (B,) int32
    t_s: np.ndarray  # (B,) float64
    label: np.ndarray  # (B,) int8
    ego_xy_m: np.ndarray  # (B, 2) float64

    @property
    def run_start(self) -> np.ndarray:
        """(B,) the first row of each row's run."""
        new = np.flatnonzero(np.r_[True, self.run[1:] != self.run[:-1]])[: len(self.run)]
        return np.repeat(new, np.diff(np.append(new, len(self.run))))


def _select(parts: list[PartRows], ranks: list[dict[str, int]], horizon_s: float) -> _Selected:
    """The eligible rows of part i's runs that `ranks[i]` ranks (scenario id → rank), in window
    order ((rank, frame)), labelled for H."""
    if not parts:
        parts, ranks = [PartRows.empty()], [{}]

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    run = np.concatenate([np.array([*(rank.get(n, -1) for n in p.names), -1])[p.run]
                          for p, rank in zip(parts, ranks, strict=True)])
    at = np.flatnonzero(run >= 0)
    key = run[at] << 32 | (cat("frame")[at].astype(np.int64) + 2**31)  # (rank, frame)
    at = at[np.argsort(key, kind="stable")]  # window order; fast on runs already in order
    offsets = np.cumsum([0, *(len(p.run) for p in parts)])
    part = np.searchsorted(offsets, at, side="right") - 1
    run, frame, t_s, collided = run[at], cat("frame")[at], cat("t_s")[at], cat("collided")[at]
    run_start = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    keep = eligible_frames(t_s, collided, run_start)
    label = frame_labels(t_s, collided, horizon_s, run_start)
    return _Selected(part[keep], (at - offsets[part])[keep], run[keep], frame[keep], t_s[keep],
                     label[keep], cat("ego_xy_m")[at][keep])


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
        committed = con.sql(query("window_runs")).fetchall()
    finally:
        con.close()
    by_part: dict[Part, dict[str, int]] = {}
    for rank, (sid, ls, batch, ingest_id) in enumerate(committed):
        by_part.setdefault(((ls, batch), ingest_id), {})[sid] = rank
    parts = list(by_part)
    store, cache = PartStore(warehouse.root), part_cache()  # resolved here, not in the threads

    def path(table: str, part: Part) -> Path:
        return store.partition_dir(table, part[0]) / f"{part[1]}{PART_SUFFIX}"

    def rows_of(part: Part) -> PartRows:
        return cache.rows(part, path("frames", part)) if cache else _read_rows(
            path("frames", part))

    with ThreadPoolExecutor(READERS) as pool:
        rows = list(pool.map(rows_of, parts))
        sel = _select(rows, [by_part[p] for p in parts], horizon_s)
        counts = np.bincount(sel.part, minlength=len(parts))
        missing = sum(int(counts[i]) for i, p in enumerate(parts)
                      if not (cache and cache.has_features(p))
                      and not path("frame_features", p).is_file())
        if missing:
            raise RuntimeError(f"{missing} frames of the selected runs have no frame_features")
        features = FrameFeatures.empty(len(sel.run), FEATURES)

        grouped = np.argsort(sel.part, kind="stable")
        bounds = np.searchsorted(sel.part[grouped], np.arange(len(parts) + 1))

        def fill(i: int) -> None:
            at = grouped[bounds[i] : bounds[i + 1]]  # its rows, in window order
            if len(at) == 0:
                return
            source = path("frame_features", parts[i])
            part_features, frame = (cache.features(parts[i], source) if cache
                                    else _read_features(source))
            if not np.array_equal(frame, rows[i].frame):
                raise RuntimeError(f"{source} does not hold the rows of its frames part")
            _scatter(features, at, part_features, sel.row[at])

        list(pool.map(fill, range(len(parts))))
    ctx_row, ctx_mask = context_rows(sel.run_start, context_len)
    names = np.array([sid for sid, *_ in committed], dtype=object)
    return Windows(features, ctx_row, ctx_mask, sel.label, names[sel.run], sel.frame, sel.t_s,
                   horizon_s, FEATURES, sel.ego_xy_m)
