"""`evoeye-knn` and `evoeye-forest`: the paper's loop with a smoothed feedback potential.

The same seed selection and density-aware mutation as `evoeye`, with the region potential q_δ
replaced. In 10–20 dimensions the δ-box around a record holds almost no other record, so q_δ is
the record's own feedback and predicts nothing about its neighbourhood. Here q is the feedback
predicted at the record from the others:

* `evoeye-knn` — μ + σ (population) of f̄ over the k = 10 nearest records in normalised θ
  (Chebyshev, the δ-box's metric; the record itself included, as in S_δ): the paper's potential
  over a neighbourhood that always holds k records;
* `evoeye-forest` — a forest's out-of-bag prediction of f̄ (each record predicted by the
  trees that did not see it), so a record's own feedback does not count.

If the feedback is predictable in θ, these steer; if not, they behave like `no-feedback` with
noise. The smoother is fitted once per batch (the loop's N_round proposals) on the records known
at the batch's start (protocol.py, "Batches"); the records added during the batch get the
smoother's prediction at their θ.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from sklearn.ensemble import ExtraTreesRegressor
from sklearn.neighbors import NearestNeighbors

from evoeye.evolve.search.feedback import normalise_feedback
from evoeye.evolve.search.mutation import EPSILON, exploit_probability
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.strategies import DensityStrategy
from evoeye.evolve.search.surrogate import MIN_SAMPLES_LEAF, N_TREES
from evoeye.scenarios import DEFAULT_DELTA, LogicalScenario

KNN_K = 10
MIN_SCORED = 3  # fewer scored records: no smoother, every potential is equal (p = 1)

# fit on the batch's scored records (u (s, dim), f̄ (s,)) and rng → q at the batch's records
# (s,) and a predictor of q at other points (c, dim) → (c,)
Smoother = Callable[[np.ndarray, np.ndarray, np.random.Generator],
                    tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]]


def knn_smoother(u: np.ndarray, fbar: np.ndarray,
                 rng: np.random.Generator) -> tuple[np.ndarray, Callable]:
    """q = μ + σ of f̄ over the KNN_K nearest scored records (Chebyshev)."""
    index = NearestNeighbors(n_neighbors=min(KNN_K, len(u)), metric="chebyshev",
                             algorithm="kd_tree").fit(u)  # no OpenMP: cheap in one thread

    def q(at: np.ndarray) -> np.ndarray:
        near = fbar[index.kneighbors(at, return_distance=False)]  # (c, k)
        return near.mean(axis=1) + near.std(axis=1)

    return q(u), q


def forest_smoother(u: np.ndarray, fbar: np.ndarray,
                    rng: np.random.Generator) -> tuple[np.ndarray, Callable]:
    """q = a forest's out-of-bag prediction of f̄ (its prediction at other points): extra-trees
    on bootstrap samples (a random forest's exhaustive splits cost ≈ 3.5× as much)."""
    model = ExtraTreesRegressor(n_estimators=N_TREES, min_samples_leaf=MIN_SAMPLES_LEAF,
                                bootstrap=True, oob_score=True,
                                random_state=int(rng.integers(2**31 - 1)), n_jobs=1).fit(u, fbar)
    own = np.asarray(model.oob_prediction_, dtype=float)
    missing = ~np.isfinite(own)  # a record no tree left out (unlikely with 100 trees)
    own[missing] = model.predict(u[missing]) if missing.any() else own[missing]
    return own, model.predict


SMOOTHERS: dict[str, Smoother] = {"evoeye-knn": knn_smoother, "evoeye-forest": forest_smoother}


class SmoothedFeedbackStrategy(DensityStrategy):
    """Density-aware mutation steered by a smoothed feedback potential, fitted once per batch."""

    def __init__(self, space: LogicalScenario, seed: int, name: str, delta: float = DEFAULT_DELTA,
                 epsilon: float = EPSILON, batch: int = 20) -> None:
        super().__init__(space, seed, potential=None, name=name, delta=delta,  # type: ignore[arg-type]
                         epsilon=epsilon)
        self.smoother = SMOOTHERS[name]
        self.batch = batch
        self._fitted: tuple[int, np.ndarray, Callable] | None = None  # batch, q of its basis

    def exploit_probabilities(self, records: Records, k: int | None = None) -> np.ndarray:
        """p (n,) from the potential smoothed over the records known at proposal k's batch
        start (all records when k is None)."""
        j = 0 if k is None else k % self.batch
        basis, b = records.n - j, -1 if k is None else k // self.batch
        u = self.space.normalise(records.params)
        if self._fitted is None or self._fitted[0] != b or k is None:
            fbar = normalise_feedback(records.feedback[:basis])  # (basis,)
            scored = np.flatnonzero(np.isfinite(fbar))
            if len(scored) < MIN_SCORED:
                q_basis, predict = np.zeros(basis), (lambda at: np.zeros(len(at)))
            else:
                rng = np.random.default_rng([self.seed, max(b, 0), 1])
                q_scored, predict = self.smoother(u[scored], fbar[scored], rng)
                q_basis = predict(u[:basis]) if len(scored) < basis else q_scored
                q_basis[scored] = q_scored
            self._fitted = (b, q_basis, predict)
        _, q_basis, predict = self._fitted
        q = np.concatenate([q_basis, predict(u[basis:]) if records.n > basis else []])
        return exploit_probability(q, self.epsilon)

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        super().replay(params, fitness)
        self._fitted = None


def smoothed(name: str) -> Callable[..., SmoothedFeedbackStrategy]:
    """The factory of the smoothed-feedback strategy `name` (a key of SMOOTHERS)."""
    def make(space: LogicalScenario, seed: int, delta: float = DEFAULT_DELTA,
             epsilon: float = EPSILON, batch: int = 20) -> SmoothedFeedbackStrategy:
        return SmoothedFeedbackStrategy(space, seed, name, delta, epsilon, batch)

    return make
