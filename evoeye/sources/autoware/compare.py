"""The same runs' windows in two warehouses — natively ingested and imported from their bags —
matched frame by frame, and how far apart their features are (the round trip's measure)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from evoeye.paths import DataRoot
from evoeye.store import load_windows

FEATURE_GROUPS = ("perception", "prediction", "plan", "plan_info", "control")


@dataclass
class Matched:
    """The windows of the frames both warehouses have, in the same order."""

    native: dict[str, np.ndarray]  # Windows.arrays of the native ingest
    imported: dict[str, np.ndarray]  # … of the import
    scenario_id: np.ndarray  # (B,) each window's run
    left_out: int  # native windows without an imported frame


def matched_windows(native: DataRoot, imported: DataRoot, scenario_ids: Sequence[str],
                    context_len: int) -> Matched:
    """The runs' windows in both warehouses, matched by (run, frame). An imported run's last
    frame closes only when a later odometry message arrives, so a realistic-rate import may
    lack it."""
    a = load_windows(native, list(scenario_ids), context_len=context_len)
    b = load_windows(imported, list(scenario_ids), context_len=context_len)
    keys = [np.char.add(np.char.add(w.scenario_id.astype(str), "/"), w.frame.astype(str))
            for w in (a, b)]
    common = np.intersect1d(*keys)
    native_rows, imported_rows = (np.flatnonzero(np.isin(k, common)) for k in keys)
    return Matched(a.arrays(native_rows), b.arrays(imported_rows),
                   a.scenario_id[native_rows], len(a) - len(common))


def feature_gaps(a: dict[str, np.ndarray], b: dict[str, np.ndarray], name: str,
                 q: float = 95.0) -> np.ndarray:
    """The q-th percentile of |b − a| of feature group `name` over the slots both fill (the
    same obstacle or point; every window of a group without slots), per value of a slot,
    flattened: (features,) for perception and plan, (K·2,) for prediction (its points in
    order), (L·features,) for plan_info and control."""
    diff = np.abs(a[name].astype(np.float64) - b[name])  # (B, L, [slots,] …)
    if f"{name}_mask" in a:
        diff = diff[a[f"{name}_mask"] & b[f"{name}_mask"]]  # (filled slots, …)
    return np.percentile(diff.reshape(len(diff), -1), q, axis=0)
