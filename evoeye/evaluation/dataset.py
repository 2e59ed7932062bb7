"""The windows a monitor is evaluated on: one split of one logical scenario, with run outcomes.

The windows hold eligible frames only (`load_windows`, view eligible_frames): a frame at or
after a run's first collision is no sample of "collision ahead or not" — a run of the paper's
setup ends at the collision — so it enters no calibration and no metric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evoeye.paths import DataRoot
from evoeye.store import RunFilter, SplitSpec, Warehouse, load_windows
from evoeye.store.selection import Runs
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S, Windows


@dataclass
class SplitWindows:
    """The windows of one split and, per window, its run's collision time (+inf if none)."""

    logical_scenario: str
    split: str
    windows: Windows
    collision_time_s: np.ndarray  # (B,) float64, tau_col of the window's run

    def __len__(self) -> int:
        return len(self.windows)

    @property
    def n_scenarios(self) -> int:
        return len(np.unique(self.windows.scenario_id))

    @property
    def n_violations(self) -> int:
        _, first = np.unique(self.windows.scenario_id, return_index=True)
        return int(np.isfinite(self.collision_time_s[first]).sum())

    def stats(self) -> dict[str, int]:
        """Scenarios, violations, (eligible) frames and unsafe frames of the split."""
        return {
            "scenarios": self.n_scenarios,
            "violations": self.n_violations,
            "frames": len(self.windows),
            "unsafe_frames": int(self.windows.label.sum()),
        }


def narrow(windows: Windows, context_len: int) -> Windows:
    """The same windows with only their newest `context_len` slots (an L-window's suffix is
    the shorter window: windows.sql pads at the start of a run)."""
    if context_len > windows.context_len:
        raise ValueError(f"cannot widen windows of L={windows.context_len} to {context_len}")
    if context_len == windows.context_len:
        return windows
    return Windows(
        windows.features, windows.context[:, -context_len:],
        windows.context_mask[:, -context_len:], windows.label, windows.scenario_id,
        windows.frame, windows.t_s, windows.horizon_s, windows.spec, windows.ego_xy_m,
    )


def collision_times(root: Warehouse | DataRoot,
                    logical_scenario: str) -> dict[str, float]:
    """scenario_id → tau_col in s (+inf for runs without a collision)."""
    wh = root if isinstance(root, Warehouse) else Warehouse(root)
    rows = wh.query("run_outcomes", logical_scenario=logical_scenario).to_pylist()
    return {
        r["scenario_id"]: float(r["collision_time_s"])
        if r["collided"] and r["collision_time_s"] is not None else np.inf
        for r in rows
    }


def load_split(
    root: Warehouse | DataRoot,
    logical_scenario: str,
    split: str,
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    *,
    context_len: int = DEFAULT_CONTEXT_LEN,
    horizon_s: float = DEFAULT_HORIZON_S,
) -> SplitWindows:
    """Every window of one split of one logical scenario, with its run's collision time."""
    runs = RunFilter(logical_scenario=logical_scenario, split=split, splits=splits)
    return load_runs(root, logical_scenario, runs, split, context_len=context_len,
                     horizon_s=horizon_s)


def load_runs(
    root: Warehouse | DataRoot,
    logical_scenario: str,
    runs: Runs,
    name: str,
    *,
    context_len: int = DEFAULT_CONTEXT_LEN,
    horizon_s: float = DEFAULT_HORIZON_S,
) -> SplitWindows:
    """Every window of any selection of `logical_scenario`'s runs (a RunFilter, ids or SQL),
    with its run's collision time; `name` labels the selection."""
    wh = root if isinstance(root, Warehouse) else Warehouse(root)
    windows = load_windows(wh, runs, context_len=context_len, horizon_s=horizon_s)
    tau = collision_times(wh, logical_scenario)
    ids, inverse = np.unique(windows.scenario_id.astype(str), return_inverse=True)
    col = np.array([tau[i] for i in ids], dtype=np.float64)[inverse.reshape(-1)]
    return SplitWindows(logical_scenario, name, windows, col)
