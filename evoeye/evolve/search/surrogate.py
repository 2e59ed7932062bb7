"""What the surrogate strategies share: batches, a candidate pool, forest spread, diverse picks.

A surrogate strategy fits a cheap model g(θ) on the records once per batch (the loop's N_round
proposals), scores a large candidate set with it and serves the batch:

1. candidates — 2**13 = 8192 points of a Sobol' sequence scrambled per batch, or in pool mode
   the pool's rows unused when the batch was chosen;
2. score — the subclass's acquisition score per candidate (higher is better), or None while the
   records cannot fit a model yet (then the whole batch is uniform);
3. picks — the top 5·n by score, thinned to n by k-means++ seeding weighted by rank
   (`sklearn.cluster.kmeans_plusplus`), so a batch spreads over the promising regions instead
   of piling into one;
4. a share `explore` (default 25 %) of the batch is uniform draws (uniform over the unused rows
   in pool mode), so a wrong model still sees the whole space; the batch is served in a seeded
   random order, so a round cut short by the budget drops a random part of it.

Batch b draws from `default_rng([seed, b])` only and reads the first `records.n − k % batch`
records (protocol.py, "Batches"), so the same seed and records give the same batch, resumed
or not.
"""

from __future__ import annotations

import numpy as np
from sklearn.cluster import kmeans_plusplus
from sklearn.ensemble import ExtraTreesRegressor

from evoeye.evolve.search.pool import CandidatePool
from evoeye.evolve.search.protocol import Proposal, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.sobol import sobol_points
from evoeye.evolve.search.strategies import BatchedStrategy
from evoeye.scenarios import LogicalScenario

EXPLORE = 0.25  # share of each batch drawn uniformly
CANDIDATES_LOG2 = 13  # 2**13 Sobol' candidates per batch outside pool mode
TOP_FACTOR = 5  # the diverse picks are thinned from the top TOP_FACTOR · n candidates
MIN_RECORDS = 10  # fewer usable records than this: no model yet, the batch is uniform
N_TREES = 100
MIN_SAMPLES_LEAF = 3  # outcomes are noisy (a seed can flip a collision): no leaf of one run


def forest(u: np.ndarray, y: np.ndarray, rng: np.random.Generator) -> ExtraTreesRegressor:
    """Extra-trees fitted on normalised θ (n, dim) → y (n,), seeded from rng (single thread)."""
    model = ExtraTreesRegressor(n_estimators=N_TREES, min_samples_leaf=MIN_SAMPLES_LEAF,
                                random_state=int(rng.integers(2**31 - 1)), n_jobs=1)
    return model.fit(u, y)


def tree_spread(model: ExtraTreesRegressor, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(μ, σ), each (c,): the mean and the spread (population std) of the trees' predictions."""
    per_tree = np.stack([t.predict(u) for t in model.estimators_])  # (trees, c)
    return per_tree.mean(axis=0), per_tree.std(axis=0)


def predicted(u_records: np.ndarray, y: np.ndarray, u: np.ndarray,
              rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray] | None:
    """(μ, σ) at candidates u (c, dim) of a forest fitted on the records' normalised θ
    (n, dim) → y (n,) where y is finite; None with fewer than MIN_RECORDS such records or
    when y is constant over them (nothing to learn)."""
    known = np.isfinite(y)
    if known.sum() < MIN_RECORDS or np.ptp(y[known]) == 0:
        return None
    return tree_spread(forest(u_records[known], y[known], rng), u)


def diverse_top(u: np.ndarray, score: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """n indices of candidates u (c, dim): the top TOP_FACTOR·n by score (ties: lower index),
    thinned by k-means++ seeding with weights falling linearly with the rank."""
    top = np.argsort(-score, kind="stable")[: TOP_FACTOR * n]
    if len(top) <= n:
        return top
    weight = np.arange(len(top), 0, -1, dtype=float)
    _, picked = kmeans_plusplus(u[top], n, sample_weight=weight,
                                random_state=int(rng.integers(2**31 - 1)))
    return top[picked]


class BatchedSurrogate(BatchedStrategy):
    """A strategy that fits a surrogate once per batch; subclasses define `score`."""

    name = ""

    def __init__(self, space: LogicalScenario, seed: int, batch: int = 20,
                 explore: float = EXPLORE) -> None:
        if not 0.0 <= explore <= 1.0:
            raise StrategyError(f"{self.name}: explore must be in [0, 1], got {explore}")
        super().__init__(space, seed, batch)
        self.explore = explore

    def score(self, records: Records, u: np.ndarray,
              rng: np.random.Generator) -> np.ndarray | None:
        """Acquisition score (c,) of candidates u (c, dim) normalised, higher is better; None
        when the records cannot fit the surrogate yet."""
        raise NotImplementedError

    def _choose(self, records: Records, b: int, pool: CandidatePool | None) -> list[Proposal]:
        """Batch b: model picks and uniform draws, in a seeded random order."""
        rng = np.random.default_rng([self.seed, b])
        if pool is None:
            rows, u = None, sobol_points(self.space.dim, CANDIDATES_LOG2, rng)
        else:
            rows = pool.unused(records)
            u = pool.u[rows]
        n = min(self.batch, len(u))
        n_model = n - int(round(self.explore * n))
        score = self.score(records, u, rng) if n_model else None
        model = diverse_top(u, score, n_model, rng) if score is not None else np.empty(0, int)
        n_uniform = n - len(model)
        if rows is None:
            picks = [(self.space.denormalise(u[i]), self.name, None) for i in model]
            picks += [(x, "uniform", None) for x in self.space.sample(rng, n_uniform)]
        else:
            rest = np.setdiff1d(np.arange(len(rows)), model)
            drawn = rng.choice(rest, size=n_uniform, replace=False)
            picks = [(pool.rows[rows[i]], kind, int(rows[i]))
                     for ids, kind in ((model, self.name), (drawn, "uniform")) for i in ids]
        return [Proposal(x=np.clip(picks[i][0], self.space.low, self.space.high).copy(),
                         kind=picks[i][1], pool_index=picks[i][2])
                for i in rng.permutation(len(picks))]
