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


def threshold_metrics(scores: np.ndarray, labels: np.ndarray, threshold: float,
                      reachable: bool = True) -> dict[str, Any]:
    """Frame-level precision, recall, F1 and realised FPR of alarms at `threshold`; precision,
    recall and F1 are None at a threshold whose target FPR was unreachable."""
    labels = np.asarray(labels).astype(bool)
    alarm = alarms(scores, threshold)
    tp, fp = int((alarm & labels).sum()), int((alarm & ~labels).sum())
    fn, tn = int((~alarm & labels).sum()), int((~alarm & ~labels).sum())
    precision = tp / (tp + fp) if tp + fp else 0.0
    recall = tp / (tp + fn) if tp + fn else 0.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    rates = {"precision": precision, "recall": recall, "f1": f1} if reachable else dict.fromkeys(
        ("precision", "recall", "f1"))
    return {"threshold": float(threshold), **rates, "fpr": fp / (fp + tn) if fp + tn else 0.0,
            "reachable": reachable}


def split_metrics(scores: np.ndarray, labels: np.ndarray, thresholds: Thresholds
                  ) -> dict[str, Any]:
    """Ranking metrics plus, per calibrated FPR (key "fpr_0.05", …), the threshold metrics."""
    out: dict[str, Any] = ranking_metrics(scores, labels)
    for fpr, thr in sorted(thresholds.by_fpr.items(), reverse=True):
        out[f"fpr_{fpr:g}"] = threshold_metrics(scores, labels, thr, thresholds.reachable(fpr))
    return out


def thresholds_to_json(thresholds: Thresholds) -> dict[str, float]:
    return {f"{fpr:g}": thr for fpr, thr in sorted(thresholds.by_fpr.items(), reverse=True)}


def thresholds_from_json(d: dict[str, float],
                         calibration: dict[str, dict] | None = None) -> Thresholds:
    """Thresholds from a card's "thresholds" and, if it has one, its "calibration"."""
    calibration = calibration or {}
    return Thresholds({float(fpr): float(thr) for fpr, thr in d.items()},
                      {float(f): float(c["realised_fpr"]) for f, c in calibration.items()
                       if c.get("realised_fpr") is not None},
                      frozenset(float(f) for f, c in calibration.items() if not c["reachable"]))


def thresholds_to_card(thresholds: Thresholds) -> dict[str, dict]:
    """The card (or meta.json) entries of calibrated thresholds: "thresholds" (target FPR →
    threshold) and "calibration" (target FPR → the FPR realised on validation, reachable)."""
    return {"thresholds": thresholds_to_json(thresholds),
            "calibration": {f"{fpr:g}": {"realised_fpr": thresholds.realised_fpr.get(fpr),
                                         "reachable": thresholds.reachable(fpr)}
                            for fpr in sorted(thresholds.by_fpr, reverse=True)}}


def thresholds_from_card(card: dict[str, Any]) -> Thresholds:
    """The thresholds a card (or meta.json) records; cards written before calibration was
    recorded have no realised FPR and count every target as reachable."""
    return thresholds_from_json(card.get("thresholds", {}), card.get("calibration"))
