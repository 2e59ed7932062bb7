"""Monitor-oriented feedback (paper §IV-C, eq. "scenario-feedback"): how wrong the monitor is.

f_r(x) = mean |ŷ − y| over the runtime contexts of run x, under the monitor of round r. A high
value means the current monitor performs poorly on that scenario. The mutation reads the
*normalised* feedback f̄, min–max scaled over all executed records so that the region potentials
of different rounds are on the same [0, 1] scale however well the monitor has learned.

ŷ is meant as the probability of a collision within H. A FusionMonitor trained with BCE
`pos_weight` = w (negatives / positives) does not output that: at the optimum of the weighted
loss its odds are w times the true odds, so safe contexts score high and |ŷ − y| is mostly false
alarms (measured: 77–92 % of the feedback of D_init under G_0). `prior_corrected` undoes the
shift, ŷ = σ(logit − log w); campaigns use it with `feedback="prior-corrected"`. Being monotone it
changes no detection metric, only which runs the feedback calls wrong.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_FLAT = 1e-12  # a feedback spread below this counts as "all equal"


@dataclass(frozen=True)
class ScenarioFeedback:
    """Per-scenario feedback: unique ids (sorted), f_r per id, and how many contexts each had."""

    scenario_id: np.ndarray  # (S,) sorted unique ids
    feedback: np.ndarray  # (S,) mean |ŷ − y| in [0, 1]
    n_contexts: np.ndarray  # (S,) int

    def aligned(self, ids: np.ndarray) -> np.ndarray:
        """Feedback in the order of `ids` (e.g. the loop's records); NaN for ids with no context."""
        ids = np.asarray(ids)
        out = np.full(ids.shape, np.nan)
        if len(self.scenario_id) == 0:
            return out
        pos = np.searchsorted(self.scenario_id, ids)
        pos_c = np.minimum(pos, len(self.scenario_id) - 1)
        found = (pos < len(self.scenario_id)) & (self.scenario_id[pos_c] == ids)
        out[found] = self.feedback[pos_c[found]]
        return out

    def as_dict(self) -> dict[str, float]:
        return {str(k): float(v) for k, v in zip(self.scenario_id, self.feedback, strict=True)}


def scenario_feedback(
    scores: np.ndarray, labels: np.ndarray, scenario_ids: np.ndarray
) -> ScenarioFeedback:
    """f_r(x) for every scenario at once from per-context scores ŷ (B,), labels y (B,), ids (B,)."""
    scores = np.asarray(scores, dtype=float)
    labels = np.asarray(labels)
    scenario_ids = np.asarray(scenario_ids)
    if not (scores.ndim == labels.ndim == scenario_ids.ndim == 1):
        raise ValueError("scores, labels and scenario_ids must be 1-D")
    if not (len(scores) == len(labels) == len(scenario_ids)):
        raise ValueError(
            f"length mismatch: {len(scores)} scores, {len(labels)} labels, "
            f"{len(scenario_ids)} scenario ids"
        )
    if not np.isfinite(scores).all():
        raise ValueError("scores must be finite")
    y = labels.astype(float)
    if not np.isin(y, (0.0, 1.0)).all():
        raise ValueError("labels must be 0 or 1")
    ids, inverse = np.unique(scenario_ids, return_inverse=True)
    n = np.bincount(inverse, minlength=len(ids))
    err_sum = np.bincount(inverse, weights=np.abs(scores - y), minlength=len(ids))
    return ScenarioFeedback(scenario_id=ids, feedback=err_sum / np.maximum(n, 1), n_contexts=n)


def scenario_disagreement(scores: np.ndarray, scenario_ids: np.ndarray) -> ScenarioFeedback:
    """A committee's disagreement per scenario: the mean over its contexts of the spread
    (population std) of K members' scores (K, B) of each context; ids (B,)."""
    scores = np.asarray(scores, dtype=float)
    if scores.ndim != 2 or scores.shape[0] < 2:
        raise ValueError(f"scores must be (K >= 2 members, B contexts), got {scores.shape}")
    spread = scores.std(axis=0)  # (B,)
    # |spread − 0| per context, grouped by scenario as the feedback is
    return scenario_feedback(spread, np.zeros(len(spread)), scenario_ids)


def prior_corrected(scores: np.ndarray, pos_weight: float) -> np.ndarray:
    """σ(logit(ŷ) − log w): the probabilities of a model trained with BCE pos_weight = w."""
    if not pos_weight > 0:
        raise ValueError(f"pos_weight must be > 0, got {pos_weight}")
    s = np.clip(np.asarray(scores, dtype=float), 1e-12, 1.0 - 1e-12)
    logit = np.log(s) - np.log1p(-s) - np.log(pos_weight)
    return 1.0 / (1.0 + np.exp(-logit))


def normalise_feedback(feedback: np.ndarray) -> np.ndarray:
    """f̄: min–max scaling of f_r over all executed records to [0, 1]; NaN (unscored) stays NaN.

    When every scored record has the same feedback there is no signal to rank them: all get 0,
    which makes every region potential equal and so every exploit probability p_δ = 1.
    """
    f = np.asarray(feedback, dtype=float)
    out = np.full(f.shape, np.nan)
    scored = np.isfinite(f)
    if not scored.any():
        return out
    lo, hi = f[scored].min(), f[scored].max()
    out[scored] = 0.0 if hi - lo < _FLAT else (f[scored] - lo) / (hi - lo)
    return out
