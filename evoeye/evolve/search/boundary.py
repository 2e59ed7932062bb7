"""`boundary`: level-set sampling where a surrogate of the safety margin is near 0 and unsure.

The margin. Both per-run gap measures the records hold are clipped at 0 for every collision
(`min_distance_m` is a footprint distance, criticality is gap / 10 m), and the simulator does
not measure how deep a collision went. So the surrogate learns a *signed* margin in metres:
a collision-free run's minimum ego–actor footprint gap (capped at 10 m, the criticality scale:
beyond it a run is simply safe), a collision −1 m. Where every run collides or every run passes,
the level set 0 lies between them, at the failure boundary itself; where the outcome is mixed,
a forest averages the two and crosses 0 where P(collision) · 1 m = (1 − P(collision)) ·
E[gap | no collision], so a half-colliding region is on the level when its safe runs pass
within 1 m. A collision classifier beside a gap regressor would need two models and a rule to
combine them; a classifier alone would throw away the near misses, the only signal when
failures are rare.

The score. Extra-trees on normalised θ, with μ and σ the mean and the spread of its trees'
predictions; the straddle score 1.96 σ − |μ| (Bryan et al., NeurIPS 2005) is high where the
predicted margin is near 0 and the trees disagree. Batches, diversity and the uniform share
come from `BatchedSurrogate`.
"""

from __future__ import annotations

import numpy as np

from evoeye.evolve.search.fitness import CRITICALITY_SCALE_M
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.surrogate import BatchedSurrogate, predicted

COLLISION_MARGIN_M = -1.0  # the signed margin a collision counts as
STRADDLE_Z = 1.96


def signed_margin_m(records: Records) -> np.ndarray:
    """(n,) the runs' signed safety margin in metres: the footprint gap (criticality · 10 m,
    so capped at 10 m) without a collision, COLLISION_MARGIN_M with one; NaN if unknown."""
    gap_m = np.asarray(records.fitness, dtype=float) * CRITICALITY_SCALE_M
    return np.where(records.collided, COLLISION_MARGIN_M, gap_m)


class BoundaryStrategy(BatchedSurrogate):
    """Straddle sampling of the signed margin's level set 0 (see the module docstring)."""

    name = "boundary"

    def score(self, records: Records, u: np.ndarray,
              rng: np.random.Generator) -> np.ndarray | None:
        y = signed_margin_m(records)
        fit = predicted(self.space.normalise(records.params), y, u, rng)
        if fit is None:
            return None
        mu, sigma = fit
        return STRADDLE_Z * sigma - np.abs(mu)
