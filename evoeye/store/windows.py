"""Training windows: runtime contexts c_t (Definition 2) with labels y_t (Definition 1), from SQL.

`warehouse/queries/windows.sql` returns every eligible frame of the selected runs (none at or
after a run's collision: view eligible_frames) with its label, its monitor inputs (table
frame_features), the ego's localization estimate and the rows of its L context frames (`ctx_row`,
`ctx_mask`). The frames' inputs are kept once; a window is `features[ctx_row]`, gathered when
asked for (all at once, or per training batch), so N frames cost N feature rows, not N·L.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from evoeye.paths import DataRoot
from evoeye.store.catalog import Warehouse
from evoeye.store.features import FEATURES, FeatureSpec, FrameFeatures, unpack
from evoeye.store.selection import Runs, select_runs
from evoeye.store.sqlfiles import query

if TYPE_CHECKING:  # torch is imported when tensors are asked for, not by the SQL-only CLI
    import torch

DEFAULT_CONTEXT_LEN = 5  # L, paper §V "Implementation Settings"
DEFAULT_HORIZON_S = 3.0  # H
BATCH_ROWS = 65_536  # rows of windows.sql fetched at a time


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


def _list_matrix(col: pa.Array | pa.ChunkedArray, width: int) -> np.ndarray:
    """A list column whose rows all have `width` items → (rows, width) numpy array."""
    if isinstance(col, pa.ChunkedArray):
        col = col.combine_chunks()
    return col.flatten().to_numpy(zero_copy_only=False).reshape(-1, width)


class _WindowsBuilder:
    """Collects the batches of windows.sql, which arrive in any order.

    Frame inputs are copied in arrival order (sequential writes); the per-window arrays go to
    their `row`, and context rows are translated to arrival positions at the end.
    """

    def __init__(self, n_frames: int, context_len: int, horizon_s: float, spec: FeatureSpec):
        self.features = FrameFeatures.empty(n_frames, spec)
        self.arrival = np.full(n_frames, -1, np.int64)  # row → position in self.features
        self.context = np.zeros((n_frames, context_len), np.int64)  # in rows, until build()
        self.context_mask = np.zeros((n_frames, context_len), bool)
        self.label = np.zeros(n_frames, np.int8)
        self.scenario_id = np.empty(n_frames, object)
        self.frame = np.zeros(n_frames, np.int32)
        self.t_s = np.zeros(n_frames, np.float64)
        self.ego_xy_m = np.zeros((n_frames, 2), np.float64)
        self.n_arrived = 0
        self.horizon_s, self.spec = horizon_s, spec

    def add(self, batch: pa.RecordBatch) -> None:
        rows = batch.column("row").to_numpy()
        start, stop = self.n_arrived, self.n_arrived + len(rows)
        if stop > len(self.arrival):
            raise RuntimeError("windows.sql returned more rows than the selected runs have frames")
        self.features.fill(start, unpack(batch, self.spec))
        self.arrival[rows] = np.arange(start, stop)
        self.n_arrived = stop
        width = self.context.shape[1]
        self.context[rows] = _list_matrix(batch.column("ctx_row"), width)
        self.context_mask[rows] = _list_matrix(batch.column("ctx_mask"), width)
        self.label[rows] = batch.column("label").to_numpy()
        self.scenario_id[rows] = batch.column("scenario_id").to_numpy(zero_copy_only=False)
        self.frame[rows] = batch.column("frame").to_numpy()
        self.t_s[rows] = batch.column("t_s").to_numpy()
        for i, name in enumerate(("loc_x_m", "loc_y_m")):
            self.ego_xy_m[rows, i] = batch.column(name).to_numpy(zero_copy_only=False)

    def build(self) -> Windows:
        if self.n_arrived != len(self.arrival) or (self.arrival < 0).any():
            missing = len(self.arrival) - self.n_arrived
            raise RuntimeError(f"{missing} frames of the selected runs have no frame_features")
        return Windows(
            self.features, self.arrival[self.context], self.context_mask, self.label,
            self.scenario_id, self.frame, self.t_s, self.horizon_s, self.spec, self.ego_xy_m,
        )


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
        n_frames = con.sql(query("count_frames")).fetchall()[0][0]
        builder = _WindowsBuilder(n_frames, context_len, horizon_s, FEATURES)
        params = {"context_len": context_len, "horizon_s": float(horizon_s)}
        reader = con.sql(query("windows"), params=params).to_arrow_reader(BATCH_ROWS)
        for batch in reader:
            builder.add(batch)
    finally:
        con.close()
    return builder.build()
