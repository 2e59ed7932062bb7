"""The same runs' windows in two warehouses — natively ingested and imported from their bags —
matched frame by frame, and how far apart their features are (the round trip's measure)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evoeye.paths import DataRoot
from evoeye.store import load_windows

FEATURE_GROUPS = ("perception", "prediction", "plan", "plan_info", "control")


def matched_windows(native: DataRoot, imported: DataRoot, scenario_ids: Sequence[str],
                    context_len: int) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray],
                                               int]:
    """(native arrays, imported arrays, native windows left out): the windows of the frames
    both warehouses have, in the same order (an imported run's last frame closes only when a
    later odometry message arrives, so a realistic-rate import may lack it)."""
    a = load_windows(native, list(scenario_ids), context_len=context_len)
    b = load_windows(imported, list(scenario_ids), context_len=context_len)
    keys = [np.char.add(np.char.add(w.scenario_id.astype(str), "/"), w.frame.astype(str))
            for w in (a, b)]
    common = np.intersect1d(*keys)
    native_rows, imported_rows = (np.flatnonzero(np.isin(k, common)) for k in keys)
    return a.arrays(native_rows), b.arrays(imported_rows), len(a) - len(common)


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
