"""`sobol`: a scrambled Sobol' sequence over the scenario space, the stronger Uniform baseline.

Proposal k is point k of the sequence scrambled by the campaign seed (`scipy.stats.qmc.Sobol`),
so any prefix of the proposals covers X more evenly than as many uniform draws; the records are
not read. In pool mode each point is snapped to the nearest unused pool row
(`evoeye.evolve.search.pool`), which keeps the sequence's even spread over the pool.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

from evoeye.evolve.search.protocol import Proposal
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.strategies import CountedStrategy
from evoeye.scenarios import LogicalScenario


def sobol_points(dim: int, m: int, seed: int | np.random.Generator) -> np.ndarray:
    """The first 2**m points (2**m, dim) in [0, 1) of the Sobol' sequence scrambled by `seed`
    (a longer prefix of the same seed starts with the same points)."""
    return qmc.Sobol(dim, scramble=True, seed=seed).random_base2(m)


class SobolStrategy(CountedStrategy):
    """Point k of the seeded scrambled Sobol' sequence as proposal k."""

    name = "sobol"

    def __init__(self, space: LogicalScenario, seed: int) -> None:
        super().__init__(space, seed)
        self._points = np.empty((0, space.dim))  # a prefix of the sequence, doubled as needed

    def propose(self, records: Records | None = None) -> Proposal:
        k = self.proposals
        if k >= len(self._points):
            m = max(6, int(np.ceil(np.log2(k + 1))))
            self._points = sobol_points(self.space.dim, m, np.random.default_rng(self.seed))
        self.proposals += 1
        x = np.clip(self.space.denormalise(self._points[k]), self.space.low, self.space.high)
        return Proposal(x=x, kind="sobol")
