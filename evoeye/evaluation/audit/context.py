"""Does *where and when* the ego is give the danger away? The context-only check.

The RQ1 context-only control (`evoeye.baselines.context`: gradient boosting on the time since
start, the ego's speed and its x, y on the map, nothing a module publishes), scored out of fold
with folds grouped by run, on the batch's pre-collision frames (labels: Definition 1, H = 3 s).

RQ1 asks a monitor to beat this control by 5 AUROC points, so a batch whose
control already scores above 0.95 leaves no room for that: the scenario script, not the ADS's
messages, ranks its frames. On a batch of a few hundred runs the control trains on fewer runs
than RQ1's (≥ 1 000), so this figure is a slight underestimate of RQ1's control: passing is
necessary for the bound, not sufficient.

Beside it, the same model without the ego's speed — when and where only, the script's part.
The speed is the ADS's own doing: where the stack drives into a conflict instead of braking,
its speed shows that decision, so the gap between the two figures is how much of the control's
score comes from watching the ego rather than reading the script.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from evoeye.baselines.context import CONTEXT_INPUTS, WHERE_WHEN_INPUTS, context_classifier
from evoeye.evaluation.audit.timing import out_of_fold_scores
from evoeye.evaluation.metrics import auprc, auroc

NO_SPEED = [CONTEXT_INPUTS.index(name) for name in WHERE_WHEN_INPUTS]  # the where-when control


@dataclass(frozen=True)
class ContextAuroc:
    """Out-of-fold AUROC and AUPRC of the context-only control; None where a class is missing."""

    frames: int
    unsafe_frames: int
    runs: int
    auroc: float | None
    auprc: float | None
    where_when_auroc: float | None  # the same without the ego's speed
    where_when_auprc: float | None

    def to_dict(self) -> dict:
        return asdict(self)


def context_auroc(x: np.ndarray, labels: np.ndarray, groups: np.ndarray) -> ContextAuroc:
    """x: (N, 4) the control's inputs (`context_inputs`), labels and run ids (N,)."""
    labels, groups, x = np.asarray(labels, np.int64), np.asarray(groups), np.asarray(x, float)
    full = out_of_fold_scores(x, labels, groups, make_model=context_classifier)
    where_when = out_of_fold_scores(x[:, NO_SPEED], labels, groups, make_model=context_classifier)
    return ContextAuroc(
        frames=len(labels), unsafe_frames=int(labels.sum()), runs=len(np.unique(groups)),
        auroc=_metric(auroc, full, labels), auprc=_metric(auprc, full, labels),
        where_when_auroc=_metric(auroc, where_when, labels),
        where_when_auprc=_metric(auprc, where_when, labels),
    )


def _metric(metric, scores: np.ndarray | None, labels: np.ndarray) -> float | None:
    return None if scores is None else metric(scores, labels)
