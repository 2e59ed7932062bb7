"""The fitness every acquisition strategy's runs are scored by: criticality (minimised).

The records carry it for every run; AV-Fuzzer selects on it, the density-aware strategies do not
read it, and the RQ2 report counts near misses from it.

`risk_fitness` is a level for rare-event search (`ce-is` in the testing-efficiency protocol,
`evoeye.results.testing`): the footprint gap saturates at the lane spacing (a car passing in
the next lane is ≈ 2 m away in every run), so among runs that did not collide it hardly orders
them; the peak ratio to the supervisor's critical bounds (`evoeye.criticality.peak_risk`:
ground-truth TTC-2D and the deceleration a lead ahead requires) does.
"""

from __future__ import annotations

import numpy as np

CRITICALITY_SCALE_M = 10.0  # a min ego–actor gap of 10 m or more counts as not critical at all


def criticality(
    collided: np.ndarray | bool,
    min_distance_m: np.ndarray | float | None,
    scale_m: float = CRITICALITY_SCALE_M,
) -> np.ndarray:
    """AV-Fuzzer fitness in [0, 1]: min gap / 10 m clipped, 0 for a collision, 1 if unknown."""
    hit = np.asarray(collided, dtype=bool)
    gap_m = np.asarray(min_distance_m, dtype=float)  # None (a failed run) becomes NaN
    fit = np.where(np.isnan(gap_m), 1.0, np.clip(gap_m / scale_m, 0.0, 1.0))
    return np.where(hit, 0.0, fit)


def risk_fitness(collided: np.ndarray | bool, peak_risk: np.ndarray | float | None) -> np.ndarray:
    """A rare-event level in [0, 1] (module doc): 1 / (1 + peak risk ratio), 0 for a collision,
    1 if unknown (a failed run)."""
    hit = np.asarray(collided, dtype=bool)
    ratio = np.asarray(peak_risk, dtype=float)
    fit = np.where(np.isnan(ratio), 1.0, 1.0 / (1.0 + np.maximum(ratio, 0.0)))
    return np.where(hit, 0.0, fit)
