"""Runtime signals of a frame → the fixed-size arrays a monitor consumes.

Everything is expressed in the ego frame of the ADS's own localization (x forward, y left,
origin at the ego centre), so a monitor learns relative geometry, never absolute map positions.
The signals come as `Signals` (`evoeye.store.signals`): an Arrow frames table at ingest, one
frame's live messages at run time — one feature code for both, its arithmetic compiled
(`evoeye.store.feature_kernels`: a frame costs a few calls, N frames one loop each).
Per frame, with n = `max_obstacles`, K = `pred_points`, P = `plan_points`:

    perception       (n, 9)    PERCEPTION_FEATURES of the n nearest obstacles, nearest first
    perception_mask  (n,)      True where a slot holds an obstacle (slots fill from 0)
    prediction       (n, K, 2) predicted centre (dx_m, dy_m) at K points, every `pred_stride`-th
                               point of the ADS's prediction, ending at its horizon, of each
                               obstacle's most probable mode; obstacles ordered by the distance
                               of their first predicted point
    prediction_mask  (n,)
    plan             (P, 7)    PLAN_FEATURES at every `plan_stride`-th planned point from now
    plan_mask        (P,)      True where the plan had that point
    plan_info        (6,)      PLAN_INFO_FEATURES: target speed, one-hot decision
    control          (6,)      CONTROL_FEATURES: the command and the ego speed/accel it acts on

Truncation and padding: obstacles beyond n are dropped, farthest first; empty obstacle slots
are zeros with mask False; a prediction or plan shorter than asked repeats its last point (mask
False on the plan's repeated points). Non-finite inputs become 0. The defaults turn the ADS's
K = 30 predicted points (0.1 s apart) into 10 (0.3 s apart, up to 3 s) and its 41 planned points
(0 … 4 s) into 11 (0.4 s apart): enough resolution for a 3 s horizon, 321 floats per frame.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np
import pyarrow as pa

from evoeye.ads.messages import PLANNING_DECISIONS
from evoeye.store.signals import ArrowSignals, Signals

PERCEPTION_FEATURES = (
    "dx_m", "dy_m", "cos_dheading", "sin_dheading", "dvx_mps", "dvy_mps",
    "length_m", "width_m", "confidence",
)
PREDICTION_FEATURES = ("dx_m", "dy_m")
PLAN_FEATURES = ("t_rel_s", "dx_m", "dy_m", "cos_dheading", "sin_dheading", "speed_mps",
                 "accel_mps2")
PLAN_INFO_FEATURES = ("target_speed_mps", *(f"decision_{d}" for d in PLANNING_DECISIONS))
CONTROL_FEATURES = ("throttle", "brake", "steering_rad", "accel_cmd_mps2", "ego_speed_mps",
                    "ego_accel_mps2")


@dataclass(frozen=True)
class FeatureSpec:
    """Fixed sizes of the per-frame arrays and which raw points they keep."""

    max_obstacles: int = 8  # n
    pred_points: int = 10  # K
    pred_stride: int = 3  # keep raw prediction points stride-1, 2·stride-1, …
    plan_points: int = 11  # P
    plan_stride: int = 4  # keep raw plan points 0, stride, 2·stride, …

    def __post_init__(self) -> None:
        if min(self.max_obstacles, self.pred_points, self.pred_stride, self.plan_points,
               self.plan_stride) < 1:
            raise ValueError(f"every FeatureSpec size must be at least 1: {self}")

    @cached_property
    def pred_raw_index(self) -> np.ndarray:
        return (np.arange(self.pred_points, dtype=np.int64) + 1) * self.pred_stride - 1

    @cached_property
    def plan_raw_index(self) -> np.ndarray:
        return np.arange(self.plan_points, dtype=np.int64) * self.plan_stride


FEATURES = FeatureSpec()  # the spec the warehouse's frame_features are built with
MIN_SLICE_ROWS = 64  # `FrameFeatures.fill` copies runs this long or longer as slices


@dataclass
class FrameFeatures:
    """Monitor inputs of N frames (shapes in the module docstring, with a leading N)."""

    perception: np.ndarray  # (N, n, 9) float32
    perception_mask: np.ndarray  # (N, n) bool
    prediction: np.ndarray  # (N, n, K, 2) float32
    prediction_mask: np.ndarray  # (N, n) bool
    plan: np.ndarray  # (N, P, 7) float32
    plan_mask: np.ndarray  # (N, P) bool
    plan_info: np.ndarray  # (N, 6) float32
    control: np.ndarray  # (N, 6) float32

    def __len__(self) -> int:
        return int(self.control.shape[0])

    def arrays(self) -> dict[str, np.ndarray]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def empty(cls, n_frames: int, spec: FeatureSpec) -> FrameFeatures:
        n, k, p = spec.max_obstacles, spec.pred_points, spec.plan_points
        return cls(
            np.zeros((n_frames, n, len(PERCEPTION_FEATURES)), np.float32),
            np.zeros((n_frames, n), bool),
            np.zeros((n_frames, n, k, 2), np.float32),
            np.zeros((n_frames, n), bool),
            np.zeros((n_frames, p, len(PLAN_FEATURES)), np.float32),
            np.zeros((n_frames, p), bool),
            np.zeros((n_frames, len(PLAN_INFO_FEATURES)), np.float32),
            np.zeros((n_frames, len(CONTROL_FEATURES)), np.float32),
        )

    def fill(self, start: int, part: FrameFeatures, index: np.ndarray | None = None) -> None:
        """Copy `part` (its rows `index`, default all) into rows start, start + 1, …

        Runs of consecutive rows in `index` are copied as slices (4× faster than a gather)."""
        if index is None:
            index = np.arange(len(part))
        if len(index) == 0:
            return
        breaks = np.flatnonzero(np.diff(index) != 1) + 1
        if len(breaks) > len(index) // MIN_SLICE_ROWS:  # scattered rows: one gather
            for name, arr in part.arrays().items():
                np.take(arr, index, axis=0, out=getattr(self, name)[start : start + len(index)])
            return
        for lo, hi in zip(np.r_[0, breaks], np.r_[breaks, len(index)], strict=True):
            src, dst = int(index[lo]), start + int(lo)
            for name, arr in part.arrays().items():
                getattr(self, name)[dst : dst + hi - lo] = arr[src : src + hi - lo]


# -- per module (the arithmetic is in evoeye.store.feature_kernels) -----------------------------
EGO_COLUMNS = ("loc_x_m", "loc_y_m", "loc_heading_rad", "loc_speed_mps")
PERCEPTION_COLUMNS = ("obs_x_m", "obs_y_m", "obs_heading_rad", "obs_vx_mps", "obs_vy_mps",
                      "obs_length_m", "obs_width_m", "obs_confidence")
PLAN_COLUMNS = ("plan_x_m", "plan_y_m", "plan_heading_rad", "plan_t_rel_s", "plan_speed_mps",
                "plan_accel_mps2")
CONTROL_COLUMNS = ("ctrl_throttle", "ctrl_brake", "ctrl_steering_rad", "ctrl_accel_cmd_mps2",
                   "loc_speed_mps", "loc_accel_mps2")  # the sources of CONTROL_FEATURES


def frame_features(source: pa.Table | Signals, spec: FeatureSpec = FEATURES) -> FrameFeatures:
    """The monitor inputs of every frame of `source`, in order: an Arrow table with
    runtime_frames columns, or any `Signals` (one frame's live messages at run time)."""
    from evoeye.store import feature_kernels as kernels  # numba: imported on first use (≈ 0.5 s)

    signals = ArrowSignals(source) if isinstance(source, pa.Table | pa.RecordBatch) else source
    out = FrameFeatures.empty(len(signals), spec)
    if len(signals) == 0:
        return out
    ego = tuple(signals.scalar(name) for name in EGO_COLUMNS)
    offsets, columns = signals.columns(PERCEPTION_COLUMNS)
    kernels.perception(ego, offsets, tuple(columns), out.perception, out.perception_mask)
    outer, inner, x = signals.points("pred_x_m")
    kernels.prediction(ego, outer, inner, x, signals.points("pred_y_m")[2],
                       signals.items("pred_track_id")[1], spec.pred_raw_index, out.prediction,
                       out.prediction_mask)
    offsets, columns = signals.columns(PLAN_COLUMNS)
    kernels.plan(ego, offsets, tuple(columns), spec.plan_raw_index, out.plan, out.plan_mask)
    kernels.plan_info_and_control(
        signals.codes("plan_decision", PLANNING_DECISIONS),
        signals.scalar("plan_target_speed_mps"),
        np.array([signals.scalar(name) for name in CONTROL_COLUMNS]), out.plan_info, out.control)
    return out


# -- storage layout (table frame_features) -------------------------------------------------------
# (stored column, FrameFeatures array, count column that encodes its mask or None)
STORED = (
    ("perception", "perception_mask", "n_perceived"),
    ("prediction", "prediction_mask", "n_predicted"),
    ("plan", "plan_mask", "n_plan_points"),
    ("plan_info", None, None),
    ("control", None, None),
)
STORED_COLUMNS = tuple(c for stored in STORED for c in (stored[0], stored[2]) if c is not None)
# Each array is one BLOB per frame (schemas/warehouse/frame_features.sql): its float32 values,
# row-major, little-endian, written as Parquet FIXED_LEN_BYTE_ARRAY. Arrow reads such a column
# as one buffer that numpy views as (N, …) float32 without a copy: 4× faster than float lists.
FLOAT32 = np.dtype("<f4")


def _float32_bytes(arr: np.ndarray) -> pa.FixedSizeBinaryArray:
    """(N, …) → a column of N values of prod(…) float32 each, as bytes."""
    width = int(np.prod(arr.shape[1:])) * FLOAT32.itemsize
    flat = np.ascontiguousarray(arr, dtype=FLOAT32)
    return pa.FixedSizeBinaryArray.from_buffers(pa.binary(width), arr.shape[0],
                                                [None, pa.py_buffer(flat)])


def pack(features: FrameFeatures) -> dict[str, pa.Array]:
    """FrameFeatures → the feature columns of frame_features (masks as slot counts)."""
    columns: dict[str, pa.Array] = {}
    for name, mask, count in STORED:
        columns[name] = _float32_bytes(getattr(features, name))
        if count is not None:
            columns[count] = pa.array(getattr(features, mask).sum(axis=1), pa.int32())
    return columns


def _float32s(col: pa.Array | pa.ChunkedArray, shape: tuple[int, ...], name: str) -> np.ndarray:
    """A stored array column (fixed-size bytes as Parquet gives them, or BLOBs as DuckDB does)
    → (N, *shape) float32, a view of the column's buffer where it is one chunk."""
    if isinstance(col, pa.ChunkedArray):
        col = col.chunk(0) if col.num_chunks == 1 else col.combine_chunks()
    width = int(np.prod(shape)) * FLOAT32.itemsize
    n = len(col)
    if n == 0:
        return np.zeros((0, *shape), FLOAT32)
    if pa.types.is_fixed_size_binary(col.type) and col.type.byte_width == width:
        data, start = col.buffers()[1], col.offset * width
    elif pa.types.is_binary(col.type) or pa.types.is_large_binary(col.type):
        kind = np.int64 if pa.types.is_large_binary(col.type) else np.int32
        offsets = np.frombuffer(col.buffers()[1], kind, n + 1, col.offset * np.dtype(kind).itemsize)
        if np.any(np.diff(offsets) != width):
            raise ValueError(f"frame_features.{name} holds values of other than {width} bytes: "
                             "the warehouse was built with another FeatureSpec")
        data, start = col.buffers()[2], int(offsets[0])
    elif pa.types.is_fixed_size_binary(col.type):
        raise ValueError(f"frame_features.{name} holds {col.type.byte_width} bytes per row, "
                         f"expected {width}: the warehouse was built with another FeatureSpec")
    else:
        raise ValueError(f"frame_features.{name} is {col.type}, not float32 bytes: a warehouse "
                         "of another layout (docs/warehouse.md)")
    if col.null_count:
        raise ValueError(f"frame_features.{name} has {col.null_count} null values")
    return np.frombuffer(data, FLOAT32, n * width // FLOAT32.itemsize, start).reshape(n, *shape)


def unpack(batch: pa.RecordBatch | pa.Table, spec: FeatureSpec = FEATURES) -> FrameFeatures:
    """The feature columns of frame_features → FrameFeatures (inverse of `pack`); the arrays
    are read-only views of `batch`'s buffers where they can be."""
    empty = FrameFeatures.empty(0, spec)
    arrays: dict[str, np.ndarray] = {}
    for name, mask, count in STORED:
        arrays[name] = _float32s(batch.column(name), getattr(empty, name).shape[1:], name)
        if count is not None:
            width = getattr(empty, mask).shape[1]
            n = batch.column(count).to_numpy(zero_copy_only=False)
            arrays[mask] = np.arange(width)[None, :] < n[:, None]
    return FrameFeatures(**arrays)
