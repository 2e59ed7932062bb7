"""A regime's sets in memory: the pool's runs (outcomes and windows), and the judging sets.

The pool's windows are loaded once; a training set of pool runs is a view of them
(`RegimeData.take`: `Windows.subset` of the runs' window ranges, sharing the frame features),
so building one copies no feature. Runs simulated during a generative campaign come with
windows of their own, joined to pool runs by `concat_windows` (a copy of the frames they use).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from evoeye.evolve.search.fitness import criticality
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.efficiency.data import batch_name, boundary_ids, val_extra_ids
from evoeye.store import Warehouse, load_windows
from evoeye.store.features import FrameFeatures
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, Windows

JUDGING_SETS = ("test", "boundary")  # the sets every monitor of the study is judged on


@dataclass
class RunTable:
    """The pool's runs in a fixed order (scenario id): θ and outcome, one row each."""

    scenario_id: np.ndarray  # (m,) object
    params: np.ndarray  # (m, dim)
    collided: np.ndarray  # (m,) bool
    min_distance_m: np.ndarray  # (m,) float, NaN if unknown
    duration_s: np.ndarray  # (m,) float

    @property
    def fitness(self) -> np.ndarray:
        """Each run's criticality (AV-Fuzzer's fitness, minimised)."""
        return criticality(self.collided, self.min_distance_m)

    def __len__(self) -> int:
        return len(self.scenario_id)


def _run_table(data: DataRoot, batch: str) -> RunTable:
    t = Warehouse(data).sql(
        "SELECT scenario_id, params, collided, min_distance_m, duration_s FROM scenarios "
        "WHERE batch = ? AND status = 'ok' ORDER BY scenario_id", [batch]).to_pydict()
    return RunTable(np.array(t["scenario_id"], dtype=object), np.array(t["params"], float),
                    np.array(t["collided"], bool),
                    np.array([np.nan if d is None else d for d in t["min_distance_m"]], float),
                    np.array(t["duration_s"], float))


def run_ranges(windows: Windows) -> dict[str, tuple[int, int]]:
    """scenario id → (first, last + 1) of its windows (a run's windows are consecutive)."""
    ids = windows.scenario_id
    return {str(ids[a]): (int(a), int(b)) for a, b in zip(*windows.run_bounds(), strict=True)}


@dataclass
class RegimeData:
    """A regime's pool (runs and windows), validation, oracle and judging sets in memory."""

    data: DataRoot
    pool: RunTable
    pool_windows: Windows
    sets: dict[str, Windows]  # val, oracle, test, boundary
    ranges: dict[str, tuple[int, int]] = field(default_factory=dict)  # pool run → windows

    def __post_init__(self) -> None:
        self.ranges = run_ranges(self.pool_windows)

    @classmethod
    def load(cls, data: DataRoot, config: EfficiencyConfig,
             context_len: int = DEFAULT_CONTEXT_LEN) -> RegimeData:
        def windows(runs) -> Windows:
            return load_windows(data, runs, context_len=context_len, horizon_s=config.horizon_s)

        def of_batch(name: str) -> Windows:
            return windows(f"SELECT scenario_id FROM scenarios WHERE batch = "
                           f"'{batch_name(name, config)}' AND status = 'ok'")

        sets = {name: of_batch(name) for name in ("val", "oracle", "test")}
        if extra := val_extra_ids(data, config):  # their unsafe windows only (data.py)
            sets["val"] = with_unsafe_windows(sets["val"], windows(extra))
        sets["boundary"] = windows(boundary_ids(data))
        return cls(data, _run_table(data, batch_name("pool", config)), of_batch("pool"), sets)

    def take(self, ids: Sequence[str]) -> Windows:
        """The windows of these pool runs, in the order given (a view: no feature copied)."""
        spans = [self.ranges[str(s)] for s in ids if str(s) in self.ranges]  # none: no window
        index = (np.concatenate([np.arange(a, b) for a, b in spans]) if spans
                 else np.zeros(0, np.int64))
        return self.pool_windows.subset(index)


def concat_windows(parts: Sequence[Windows]) -> Windows:
    """One Windows of several (each with frame features of its own): the frames they use
    copied once, their contexts re-based."""
    parts = [w for w in parts if len(w)]
    if not parts:
        raise ValueError("nothing to concatenate")
    used = [np.unique(w.context) for w in parts]
    features = FrameFeatures.empty(sum(len(u) for u in used), parts[0].spec)
    contexts, start = [], 0
    for w, rows in zip(parts, used, strict=True):
        features.fill(start, w.features, rows)
        contexts.append(start + np.searchsorted(rows, w.context))
        start += len(rows)

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(w, name) for w in parts])

    xy = None if any(w.ego_xy_m is None for w in parts) else cat("ego_xy_m")
    return Windows(features, np.concatenate(contexts), cat("context_mask"), cat("label"),
                   cat("scenario_id"), cat("frame"), cat("t_s"), parts[0].horizon_s,
                   parts[0].spec, xy)


def with_unsafe_windows(windows: Windows, more: Windows) -> Windows:
    """`windows` and the unsafe windows of `more` (label 1): its negatives are `windows`'."""
    return concat_windows([windows, more.subset(np.flatnonzero(more.label == 1))])
