"""What a monitor card records: which data (selection, fingerprint) and how well (metrics)."""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np
from sklearn.metrics import average_precision_score, roc_auc_score

from evoeye.monitor.calibration import alarms
from evoeye.monitor.protocol import Thresholds
from evoeye.store.selection import RunFilter, Runs
from evoeye.store.windows import Windows


def describe_selection(runs: Runs) -> dict[str, Any]:
    """The run selection as JSON: a RunFilter's parameters, the SQL text or the id list's hash."""
    if runs is None:
        runs = RunFilter()
    if isinstance(runs, RunFilter):
        return {"kind": "filter", "query": "warehouse/queries/select_runs.sql",
                "params": runs.params()}
    if isinstance(runs, str):
        return {"kind": "sql", "query": runs}
    ids = sorted(str(r) for r in runs)
    return {"kind": "ids", "count": len(ids),
            "sha256": hashlib.sha256("\n".join(ids).encode()).hexdigest()}


def data_summary(windows: Windows) -> dict[str, Any]:
    """Runs, frames, unsafe frames and a fingerprint: sha256 of sorted (scenario id, frames)."""
    ids, counts = np.unique(windows.scenario_id.astype(str), return_counts=True)
    text = "\n".join(f"{i}\t{c}" for i, c in zip(ids.tolist(), counts.tolist(), strict=True))
    return {
        "runs": len(ids),
        "frames": int(len(windows)),
        "unsafe_frames": int(windows.label.sum()),
        "fingerprint": hashlib.sha256(text.encode()).hexdigest()[:16],
    }


def ranking_metrics(scores: np.ndarray, labels: np.ndarray) -> dict[str, float | None]:
    """AUROC and AUPRC (average precision); None where a split lacks one of the classes."""
    labels = np.asarray(labels).astype(int)
    if labels.min(initial=0) == labels.max(initial=0):
        return {"auroc": None, "auprc": None}
    return {"auroc": float(roc_auc_score(labels, scores)),
            "auprc": float(average_precision_score(labels, scores))}


def threshold_metrics(scores: np.ndarray, labels: np.ndarray, threshold: float
                      ) -> dict[str, float]:
    """Frame-level precision, recall, F1 and realised FPR of alarms at `threshold`."""
    labels = np.asarray(labels).astype(bool)
    alarm = alarms(scores, threshold)
    tp, fp = int((alarm & labels).sum()), int((alarm & ~labels).sum())
    fn, tn = int((~alarm & labels).sum()), int((~alarm & ~labels).sum())
    precision = tp / (tp + fp) if tp + fp else 0.0
    recall = tp / (tp + fn) if tp + fn else 0.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    return {"threshold": float(threshold), "precision": precision, "recall": recall, "f1": f1,
            "fpr": fp / (fp + tn) if fp + tn else 0.0}


def split_metrics(scores: np.ndarray, labels: np.ndarray, thresholds: Thresholds
                  ) -> dict[str, Any]:
    """Ranking metrics plus, per calibrated FPR (key "fpr_0.05", …), the threshold metrics."""
    out: dict[str, Any] = ranking_metrics(scores, labels)
    for fpr, thr in sorted(thresholds.by_fpr.items(), reverse=True):
        out[f"fpr_{fpr:g}"] = threshold_metrics(scores, labels, thr)
    return out


def thresholds_to_json(thresholds: Thresholds) -> dict[str, float]:
    return {f"{fpr:g}": thr for fpr, thr in sorted(thresholds.by_fpr.items(), reverse=True)}


def thresholds_from_json(d: dict[str, float]) -> Thresholds:
    return Thresholds({float(fpr): float(thr) for fpr, thr in d.items()})
