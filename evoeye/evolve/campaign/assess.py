"""How good a monitor version is, on the fixed Test Set and on the Hard Set of G_0 (paper RQ2).

The Hard Set holds the unsafe test frames the initial monitor G_0 misses at its FPR-0.05
threshold plus the safe frames of those runs; it is selected in SQL
(`warehouse/queries/hard_set.sql`) from G_0's rows in monitor_scores, which `Assessor` writes
first if they are missing. Every version is judged at its own thresholds (calibrated on the
fixed validation split when it was trained).

The robust Hard Set (`robust_hard_set`, `warehouse/queries/robust_hard_set.sql`) holds the
unsafe test frames a strict majority of k re-seeded G_0s miss, and every safe test frame: hard
whatever G_0's training seed, and with false alarms paid on the whole Test Set. An `Assessor`
given the re-seeded G_0s judges on it too (`evoeye results`); a campaign's does not.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict

import numpy as np
import pyarrow as pa

from evoeye.evaluation.dataset import SplitWindows, load_split, narrow
from evoeye.evaluation.metrics import frame_metrics
from evoeye.evaluation.monitors import check_scores
from evoeye.monitor.families import load_calibrated
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.threads import intra_op_threads
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse
from evoeye.store.feedback import RoundMetrics
from evoeye.store.scores import ScoreRows, read_scores, scored_scenarios, write_scores
from evoeye.store.sqlfiles import query
from evoeye.store.windows import DEFAULT_HORIZON_S, Windows

HARD_SET_FPR = 0.05
FPRS = (0.05, 0.01)
SetMetrics = Callable[[np.ndarray, np.ndarray, Thresholds], dict]  # (scores, labels, thr) → figures


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


def metrics_dict(scores: np.ndarray, labels: np.ndarray, thresholds,
                 weight: np.ndarray | None = None) -> dict:
    """F1 / precision / recall at each target FPR, AUROC and AUPRC, as plain numbers; at a
    target FPR the thresholds could not reach (`reachable@…` False) the three rates are None.
    `weight`: of each frame of a weighted (stratified) set (`frame_metrics`)."""
    m = frame_metrics(scores, labels, thresholds, FPRS, weight)
    out = {"auroc": m.auroc, "auprc": m.auprc, "frames": m.frames, "unsafe": m.unsafe_frames}
    for fpr, c in m.at_fpr.items():
        out[f"f1@{fpr}"], out[f"recall@{fpr}"], out[f"precision@{fpr}"] = (
            c.f1, c.recall, c.precision)
        out[f"reachable@{fpr}"] = c.reachable
    return out


def reached(metrics: dict, metric: str) -> bool:
    """Whether `metric` (a key of `metrics_dict`, e.g. "f1@0.05") was measured: False only
    where its target FPR was unreachable; a metric of no FPR ("auroc") always was."""
    fpr = metric.partition("@")[2]
    return not fpr or metrics.get(f"reachable@{fpr}") is not False


class Assessor:
    """Judges monitor versions on one scenario's Test Set and on subsets of it: the Hard Set of
    G_0 and, given the re-seeded G_0s, the robust Hard Set."""

    @intra_op_threads()
    def __init__(self, root: DataRoot, scenario: str, g0: str, *,
                 reseeded: Sequence[str] = (),
                 splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen)
                 horizon_s: float = DEFAULT_HORIZON_S,
                 test: SplitWindows | None = None) -> None:
        """`reseeded`: the k G_0s of the robust Hard Set (G_0 first; none: no robust set).
        `test`: the Test Set's windows at any L ≥ every judged version's (default: loaded at
        G_0's L)."""
        self.root, self.scenario, self.g0, self.reseeded = root, scenario, g0, tuple(reseeded)
        g0s = {v: load_calibrated(root, v) for v in (g0, *self.reseeded)}
        self.test: SplitWindows = test if test is not None else load_split(
            root, scenario, "test", splits, context_len=g0s[g0].context_len, horizon_s=horizon_s)
        w = self.test.windows
        for monitor in g0s.values():
            ensure_scored(root, monitor, scenario, narrow(w, monitor.context_len))
        thresholds = {v: m.thresholds.at(HARD_SET_FPR) for v, m in g0s.items()}
        scores = pa.concat_tables([read_scores(root, monitor_version=v) for v in g0s])
        kw = {"logical_scenario": scenario, "horizon_s": horizon_s, "splits": splits}
        hard = hard_set(Warehouse(root), scores, monitor_version=g0, threshold=thresholds[g0],
                        **kw)
        self.masks: dict[str, np.ndarray] = {"test": np.ones(len(w), bool),  # set → (B,) bool
                                             "hard": frame_mask(hard, w)}
        if self.reseeded:
            robust = robust_hard_set(Warehouse(root), scores, **kw, thresholds={
                v: thresholds[v] for v in self.reseeded})
            self.masks["robust"] = frame_mask(robust, w)
        self._assessed: dict[str, RoundMetrics] = {}  # a version never changes

    @classmethod
    def of(cls, campaign) -> Assessor:
        """A campaign's assessor: its scenario's Test Set, its reference G_0's Hard Set."""
        cfg = campaign.config
        return cls(campaign.root, cfg.scenario, campaign.reference, splits=cfg.splits,
                   horizon_s=cfg.horizon_s)

    def sizes(self) -> dict[str, dict[str, int]]:
        """Frames and unsafe frames of every set."""
        labels = self.test.windows.label
        return {name: {"frames": int(m.sum()), "unsafe": int(labels[m].sum())}
                for name, m in self.masks.items()}

    @intra_op_threads()
    def figures(self, version: str, metrics: SetMetrics = metrics_dict) -> dict[str, dict]:
        """{set: `metrics` of `version` on it}, at the version's own thresholds."""
        monitor = load_calibrated(self.root, version)
        w = self.test.windows
        scores = check_scores(monitor, monitor.score(narrow(w, monitor.context_len)), len(w))
        return {name: metrics(scores[m], w.label[m], monitor.thresholds)
                for name, m in self.masks.items()}

    def __call__(self, version: str) -> RoundMetrics:
        """`version` on the Test Set and the Hard Set, at its own thresholds (once a version)."""
        if version not in self._assessed:
            f = self.figures(version)
            self._assessed[version] = RoundMetrics(version, test=f["test"], hard=f["hard"])
        return self._assessed[version]
