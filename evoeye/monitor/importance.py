"""Importance-weighted training: each window's loss times its run's weight p/q.

A strategy that draws runs from a proposal q ≠ p (the scenario distribution; `ce-is` draws
from a known q and records p/q per run) shifts the training set towards where q is high. A
monitor trained on it without weights learns the proposal's world — collision-rich — and is
judged on p's. With `TrainParams.importance_weights` the trainer multiplies each window's loss
by its run's weight, estimating the loss under p (`evoeye.monitor.fit`):

1. raw weights: the run's p/q, exact where the run's proposal density is known; 1 for a run
   without one (initial runs and uniform acquisitions are drawn from p itself);
2. self-normalised over the training runs (mean 1), so only ratios matter;
3. clipped at √n_runs (truncated importance sampling, Ionides 2008: with normalised weights of
   mean 1, the cap √n bounds any run's share of the loss and the variance it adds, and its
   bias vanishes as n grows); then scaled so the windows' mean weight is 1, keeping the loss on
   the scale of an unweighted one (the same learning rates apply).

`pos_weight` (negatives / positives) is then counted in weighted windows, so it balances the
classes as p has them rather than as q does. Off by default: every recorded recipe, card and
version id stays as it was.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np


def window_weights(scenario_id: np.ndarray,
                   run_ratio: Mapping[str, float] | None) -> tuple[np.ndarray, dict]:
    """((B,) weight of each window, a summary for the card) from the runs' p/q by scenario id
    (a run missing: 1); ValueError for a ratio that is not finite and > 0."""
    ids = np.asarray(scenario_id).astype(str)
    runs, inverse = np.unique(ids, return_inverse=True)
    given = run_ratio or {}
    raw = np.array([float(given.get(r, 1.0)) for r in runs])
    if not (np.isfinite(raw) & (raw > 0)).all():
        bad = runs[~(np.isfinite(raw) & (raw > 0))][0]
        raise ValueError(f"run {bad}: its weight p/q must be finite and > 0")
    w = raw / raw.mean()
    cap = math.sqrt(len(runs))
    clipped = int((w > cap).sum())
    w = np.minimum(w, cap)
    per_window = w[inverse]
    per_window = per_window / per_window.mean()
    summary = {"runs": len(runs), "weighted_runs": int(sum(r in given for r in runs)),
               "clip": round(cap, 6), "clipped_runs": clipped,
               "effective_runs": round(float(w.sum() ** 2 / (w**2).sum()), 3)}
    return per_window.astype(np.float32), summary
