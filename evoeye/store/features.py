"""Runtime signals of a frame → the fixed-size arrays a monitor consumes (pure numpy, no row loop).

Everything is expressed in the ego frame of the ADS's own localization (x forward, y left,
origin at the ego centre), so a monitor learns relative geometry, never absolute map positions.
The signals come as `Signals` (`evoeye.store.signals`): an Arrow frames table at ingest, one
frame's live messages at run time — one feature code for both.
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

    @property
    def pred_raw_index(self) -> np.ndarray:
        return (np.arange(self.pred_points) + 1) * self.pred_stride - 1

    @property
    def plan_raw_index(self) -> np.ndarray:
        return np.arange(self.plan_points) * self.plan_stride


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


# -- geometry -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class _EgoPose:
    """The ego's pose and velocity (map frame), one entry per frame — or per item (`expand`)."""

    x_m: np.ndarray
    y_m: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    heading_rad: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray

    @classmethod
    def of(cls, signals: Signals) -> _EgoPose:
        h = signals.scalar("loc_heading_rad")
        v = signals.scalar("loc_speed_mps")
        c, s = np.cos(h), np.sin(h)
        return cls(signals.scalar("loc_x_m"), signals.scalar("loc_y_m"), c, s, h, v * c, v * s)

    def expand(self, offsets: np.ndarray | None, trailing: int = 0) -> _EgoPose:
        """The pose of each item of a list column with these offsets (None: of each frame),
        with `trailing` axes of length 1 to broadcast against per-item values. One frame's pose
        is a pose of floats (numpy multiplies by a float at half the cost of broadcasting)."""
        arrays = [self.x_m, self.y_m, self.cos, self.sin, self.heading_rad, self.vx_mps,
                  self.vy_mps]
        if len(arrays[0]) == 1:
            return _EgoPose(*(float(a[0]) for a in arrays))
        if offsets is not None:
            rows = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
            arrays = [a[rows] for a in arrays]
        if trailing:
            arrays = [a.reshape(-1, *(1,) * trailing) for a in arrays]
        return _EgoPose(*arrays)

    def rotate(self, wx: np.ndarray, wy: np.ndarray) -> tuple[np.ndarray, ...]:
        """World vectors (wx, wy) → ego-frame (forward, left)."""
        return self.cos * wx + self.sin * wy, -self.sin * wx + self.cos * wy

    def to_ego(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, ...]:
        """World points → ego-frame points."""
        return self.rotate(x - self.x_m, y - self.y_m)


def _frame_of_items(offsets: np.ndarray) -> np.ndarray:
    """(M,) the frame of each item of a list column with these offsets."""
    if len(offsets) == 2:  # one frame (run time): no repeat needed
        return np.zeros(offsets[1], np.int64)
    return np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))


def _nearest_slots(
    offsets: np.ndarray, dist: np.ndarray, n_max: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For items grouped by frame: (item, frame, slot) of the n_max nearest per frame."""
    frame = _frame_of_items(offsets)
    order = np.lexsort((dist, frame))  # by frame, then distance
    slot = np.arange(len(order)) - offsets[frame[order]]
    keep = slot < n_max
    return order[keep], frame[order[keep]], slot[keep]


def _points_index(
    offsets: np.ndarray, raw_index: np.ndarray, n_values: int
) -> tuple[np.ndarray, np.ndarray]:
    """Indices (rows, len(raw_index)) into n_values values picking items `raw_index` of each
    row, the row's last item standing in past its end; and the mask of items that exist.
    Empty rows index a valid but meaningless item: callers mask them."""
    counts = np.diff(offsets)[:, None]
    idx = offsets[:-1, None] + np.minimum(raw_index[None, :], np.maximum(counts - 1, 0))
    return np.minimum(idx, max(n_values - 1, 0)), raw_index[None, :] < counts


def _finite32(a: np.ndarray) -> np.ndarray:
    """float32 of `a` with every non-finite value 0 (np.nan_to_num's result, without its cost)."""
    return np.where(np.isfinite(a), a, 0.0).astype(np.float32)


# -- per module ---------------------------------------------------------------------------------
PERCEPTION_COLUMNS = ("obs_x_m", "obs_y_m", "obs_heading_rad", "obs_vx_mps", "obs_vy_mps",
                      "obs_length_m", "obs_width_m", "obs_confidence")
PLAN_COLUMNS = ("plan_x_m", "plan_y_m", "plan_heading_rad", "plan_t_rel_s", "plan_speed_mps",
                "plan_accel_mps2")


def _perception(t: Signals, ego: _EgoPose, spec: FeatureSpec, out: FrameFeatures) -> None:
    offsets, (x, y, h, vx, vy, length, width, confidence) = t.columns(PERCEPTION_COLUMNS)
    pose = ego.expand(offsets)
    feats = np.empty((len(x), len(PERCEPTION_FEATURES)))
    feats[:, 0], feats[:, 1] = pose.to_ego(x, y)
    dh = h - pose.heading_rad
    feats[:, 2], feats[:, 3] = np.cos(dh), np.sin(dh)
    feats[:, 4], feats[:, 5] = pose.rotate(vx - pose.vx_mps, vy - pose.vy_mps)
    feats[:, 6], feats[:, 7], feats[:, 8] = length, width, confidence
    dist = np.hypot(feats[:, 0], feats[:, 1])
    item, frame, slot = _nearest_slots(offsets, dist, spec.max_obstacles)
    out.perception[frame, slot] = _finite32(feats[item])
    out.perception_mask[frame, slot] = True


def _prediction(t: Signals, ego: _EgoPose, spec: FeatureSpec, out: FrameFeatures) -> None:
    outer, inner, x = t.points("pred_x_m")  # inner: absolute into x
    y = t.points("pred_y_m")[2]
    if len(inner) <= 1 or len(x) == 0:
        return
    idx, _ = _points_index(inner, spec.pred_raw_index, len(x))  # (M, K) into x / y
    has_points = np.diff(inner) > 0
    dx, dy = ego.expand(outer, trailing=1).to_ego(x[idx], y[idx])
    # one slot per obstacle, its most probable mode: the first of its contiguous rows
    track = t.items("pred_track_id")[1]
    first = np.ones(len(track), dtype=bool)
    first[1:] = track[1:] != track[:-1]
    if len(outer) > 2:  # a new frame starts a new obstacle too
        rows = _frame_of_items(outer)
        first[1:] |= rows[1:] != rows[:-1]
    dist = np.where(has_points & first, np.hypot(dx[:, 0], dy[:, 0]), np.inf)
    item, frame, slot = _nearest_slots(outer, dist, spec.max_obstacles)
    primary = first[item]
    item, frame, slot = item[primary], frame[primary], slot[primary]
    out.prediction[frame, slot, :, 0] = _finite32(dx[item])
    out.prediction[frame, slot, :, 1] = _finite32(dy[item])
    out.prediction_mask[frame, slot] = has_points[item]


def _plan(t: Signals, ego: _EgoPose, spec: FeatureSpec, out: FrameFeatures) -> None:
    offsets, (x, y, h, t_rel, speed, accel) = t.columns(PLAN_COLUMNS)
    if len(x) == 0:
        return
    idx, mask = _points_index(offsets, spec.plan_raw_index, len(x))  # (N, P)
    pose = ego.expand(None, trailing=1)
    feats = np.empty((*idx.shape, len(PLAN_FEATURES)))
    feats[..., 1], feats[..., 2] = pose.to_ego(x[idx], y[idx])
    dh = h[idx] - pose.heading_rad
    feats[..., 3], feats[..., 4] = np.cos(dh), np.sin(dh)
    feats[..., 0], feats[..., 5], feats[..., 6] = t_rel[idx], speed[idx], accel[idx]
    has_plan = np.diff(offsets) > 0
    out.plan[has_plan] = _finite32(feats[has_plan])
    out.plan_mask[:] = mask


CONTROL_COLUMNS = ("ctrl_throttle", "ctrl_brake", "ctrl_steering_rad", "ctrl_accel_cmd_mps2",
                   "loc_speed_mps", "loc_accel_mps2")  # the sources of CONTROL_FEATURES


def _plan_info_and_control(t: Signals, out: FrameFeatures) -> None:
    code = t.codes("plan_decision", PLANNING_DECISIONS)
    info = np.zeros((len(t), len(PLAN_INFO_FEATURES)))
    info[:, 0] = t.scalar("plan_target_speed_mps")
    known = np.flatnonzero(code >= 0)
    info[known, 1 + code[known]] = 1.0
    out.plan_info[:] = _finite32(info)
    control = np.empty((len(t), len(CONTROL_FEATURES)))
    for col, name in enumerate(CONTROL_COLUMNS):
        control[:, col] = t.scalar(name)
    out.control[:] = _finite32(control)


def frame_features(source: pa.Table | Signals, spec: FeatureSpec = FEATURES) -> FrameFeatures:
    """The monitor inputs of every frame of `source`, in order: an Arrow table with
    runtime_frames columns, or any `Signals` (one frame's live messages at run time)."""
    signals = ArrowSignals(source) if isinstance(source, pa.Table | pa.RecordBatch) else source
    out = FrameFeatures.empty(len(signals), spec)
    if len(signals) == 0:
        return out
    ego = _EgoPose.of(signals)
    _perception(signals, ego, spec, out)
    _prediction(signals, ego, spec, out)
    _plan(signals, ego, spec, out)
    _plan_info_and_control(signals, out)
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
