"""`disagreement`: where K monitors disagree most, predicted over θ, with an exploration bonus.

A committee of K monitors (the campaign's G_r and K − 1 companions trained alongside it from
other seeds: `evoeye.evolve.campaign.committee`) scores every run; a run's disagreement is the
mean over its contexts of the spread of their scores (`scenario_disagreement`), the records'
`disagreement` column. Disagreement among members that saw the same data is epistemic: it is
what more data can remove, where a run's error |ŷ − y| also counts the label noise no choice of
runs reduces (acquisition.md, §1). Extra-trees regress it on normalised θ and each batch takes
the candidates of highest UCB μ + κ σ (σ: the spread of the trees), κ = 1.
"""

from __future__ import annotations

import numpy as np

from evoeye.evolve.search.records import Records
from evoeye.evolve.search.surrogate import BatchedSurrogate, predicted

UCB_KAPPA = 1.0


class DisagreementStrategy(BatchedSurrogate):
    """UCB over the forest-predicted disagreement of the records (see the module docstring)."""

    name = "disagreement"

    def score(self, records: Records, u: np.ndarray,
              rng: np.random.Generator) -> np.ndarray | None:
        y = np.asarray(records.disagreement, dtype=float)
        fit = predicted(self.space.normalise(records.params), y, u, rng)
        if fit is None:
            return None
        mu, sigma = fit
        return mu + UCB_KAPPA * sigma
