"""How good a monitor version is, on the fixed Test Set and on the Hard Set of G_0 (paper RQ2).

The Hard Set holds the unsafe test frames the initial monitor G_0 misses at its FPR-0.05
threshold plus the safe frames of those runs; it is selected in SQL
(`warehouse/queries/hard_set.sql`) from G_0's rows in monitor_scores, which `Assessor` writes
first if they are missing. Every version is judged at its own thresholds (calibrated on the
fixed validation split when it was trained).

The robust Hard Set (`robust_hard_set`, `warehouse/queries/robust_hard_set.sql`) holds the
unsafe test frames a strict majority of k re-seeded G_0s miss, and every safe test frame: hard
whatever G_0's training seed, and with false alarms paid on the whole Test Set.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pyarrow as pa

from evoeye.evaluation.dataset import SplitWindows, load_split
from evoeye.evaluation.metrics import frame_metrics
from evoeye.monitor.families import load_calibrated
from evoeye.monitor.threads import intra_op_threads
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse
from evoeye.store.feedback import RoundMetrics
from evoeye.store.scores import ScoreRows, read_scores, scored_scenarios, write_scores
from evoeye.store.sqlfiles import query
from evoeye.store.windows import DEFAULT_HORIZON_S, Windows

HARD_SET_FPR = 0.05
FPRS = (0.05, 0.01)


def _over_scores(warehouse: Warehouse, scores: pa.Table, name: str, splits: SplitSpec,
                 **params) -> pa.Table:
    """Query `name` over a monitor_scores table, with the split's parameters bound."""
    con = warehouse.connect()
    try:
        con.register("monitor_scores", scores)
        return con.sql(query(name), params={**params, **asdict(splits)}).to_arrow_table()
    finally:
        con.close()


def hard_set(warehouse: Warehouse, scores: pa.Table, *, monitor_version: str, threshold: float,
             logical_scenario: str, horizon_s: float = DEFAULT_HORIZON_S,
             splits: SplitSpec = SplitSpec()) -> pa.Table:  # noqa: B008 (frozen)
    """The Hard Set frames (scenario_id, frame, t_s, label, score) from a monitor_scores table."""
    return _over_scores(warehouse, scores, "hard_set", splits, monitor_version=monitor_version,
                        threshold=float(threshold), logical_scenario=logical_scenario,
                        horizon_s=float(horizon_s))


def robust_hard_set(warehouse: Warehouse, scores: pa.Table, *, thresholds: dict[str, float],
                    logical_scenario: str, horizon_s: float = DEFAULT_HORIZON_S,
                    splits: SplitSpec = SplitSpec()) -> pa.Table:  # noqa: B008 (frozen)
    """The robust Hard Set (`warehouse/queries/robust_hard_set.sql`): the unsafe test frames a
    strict majority of the monitors `thresholds` names (version → its FPR-0.05 threshold) miss,
    plus every safe test frame; rows (scenario_id, frame, t_s, label, missed_by)."""
    if not thresholds:
        raise ValueError("the robust Hard Set needs at least one re-seeded G_0")
    return _over_scores(warehouse, scores, "robust_hard_set", splits,
                        monitor_versions=list(thresholds),
                        thresholds=[float(t) for t in thresholds.values()],
                        logical_scenario=logical_scenario, horizon_s=float(horizon_s))


def frame_mask(frames: pa.Table, windows: Windows) -> np.ndarray:
    """(B,) bool: which windows end at a frame (scenario_id, frame) of `frames`."""
    keys = set(zip(frames.column("scenario_id").to_pylist(), frames.column("frame").to_pylist(),
                   strict=True))
    return np.array([(s, int(f)) in keys for s, f in
                     zip(windows.scenario_id.tolist(), windows.frame.tolist(), strict=True)],
                    dtype=bool)


def ensure_scored(root: DataRoot, monitor, scenario: str, windows: Windows) -> None:
    """Write `monitor`'s scores of these windows to monitor_scores unless every run of them is
    there already (the Hard Set queries read them)."""
    if not set(windows.scenario_id.tolist()) <= scored_scenarios(root, monitor.version):
        write_scores(root, ScoreRows(monitor.name, monitor.version, scenario, windows.scenario_id,
                                     windows.frame, windows.t_s, monitor.score(windows)))


def metrics_dict(scores: np.ndarray, labels: np.ndarray, thresholds) -> dict:
    """F1 / precision / recall at each target FPR, AUROC and AUPRC, as plain numbers; at a
    target FPR the thresholds could not reach (`reachable@…` False) the three rates are None."""
    m = frame_metrics(scores, labels, thresholds, FPRS)
    out = {"auroc": m.auroc, "auprc": m.auprc, "frames": m.frames, "unsafe": m.unsafe_frames}
    for fpr, c in m.at_fpr.items():
        out[f"f1@{fpr}"], out[f"recall@{fpr}"], out[f"precision@{fpr}"] = (
            c.f1, c.recall, c.precision)
        out[f"reachable@{fpr}"] = c.reachable
    return out


class Assessor:
    """Scores monitor versions on the Test Set and the Hard Set of G_0 of one scenario."""

    @intra_op_threads()
    def __init__(self, root: DataRoot, scenario: str, g0: str, *,
                 splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen)
                 horizon_s: float = DEFAULT_HORIZON_S) -> None:
        self.root = root
        monitor = load_calibrated(self.root, g0)
        self.test: SplitWindows = load_split(self.root, scenario, "test", splits,
                                             context_len=monitor.context_len,
                                             horizon_s=horizon_s)
        w = self.test.windows
        ensure_scored(self.root, monitor, scenario, w)
        hard = hard_set(Warehouse(self.root), read_scores(self.root, monitor_version=g0),
                        monitor_version=g0, threshold=monitor.thresholds.at(HARD_SET_FPR),
                        logical_scenario=scenario, horizon_s=horizon_s, splits=splits)
        self.hard = frame_mask(hard, w)
        self.context_len = monitor.context_len
        self._assessed: dict[str, RoundMetrics] = {}  # a version never changes

    @classmethod
    def of(cls, campaign) -> Assessor:
        """A campaign's assessor: its scenario's Test Set, its reference G_0's Hard Set."""
        cfg = campaign.config
        return cls(campaign.root, cfg.scenario, campaign.reference, splits=cfg.splits,
                   horizon_s=cfg.horizon_s)

    @intra_op_threads()
    def __call__(self, version: str) -> RoundMetrics:
        """`version` on the Test Set and the Hard Set, at its own thresholds (once a version)."""
        if version in self._assessed:
            return self._assessed[version]
        monitor = load_calibrated(self.root, version)
        scores = monitor.score(self.test.windows)
        labels = self.test.windows.label
        self._assessed[version] = RoundMetrics(
            version,
            test=metrics_dict(scores, labels, monitor.thresholds),
            hard=metrics_dict(scores[self.hard], labels[self.hard], monitor.thresholds),
        )
        return self._assessed[version]
