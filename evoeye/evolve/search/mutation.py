"""Density-aware mutation (paper §IV-C): exploit a seed's neighbourhood or explore the space.

For a seed x among the executed records D, S_δ(x) are the records within Chebyshev distance δ
of x on normalised parameters (x itself included: it is an executed record at distance 0).
The region's exploit potential is q_δ(x) = μ_δ(x) + σ_δ(x), the mean and *population* standard
deviation of the normalised feedback f̄ over S_δ(x); p_δ(x) = (q_δ(x) + ε) / (max_D q_δ + ε).
With probability p_δ(x) the new scenario is uniform in N_δ(x), otherwise uniform in X.

The (n, n) neighbourhood relation only changes when records are added, never when feedback is
refreshed, so `DensityIndex` keeps it as a list of neighbour pairs, extended by the new rows
only; a potential then costs O(Σ|S_δ|) instead of O(n²).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.sparse import coo_array
from scipy.spatial.distance import cdist

from evoeye.scenarios import DEFAULT_DELTA, LogicalScenario

EPSILON = 1e-6  # ε of p_δ: keeps the ratio defined when every potential is 0
_CHUNK_ROWS = 512  # rows of the distance matrix computed at once: bounds memory to 512·n floats


@dataclass(frozen=True)
class Mutation:
    """A mutated concrete scenario and whether it was drawn from the seed's neighbourhood."""

    x: np.ndarray  # (dim,) in parameter units
    local: bool


class DensityIndex:
    """Which executed records lie within δ of each other, extended as records are appended."""

    def __init__(self, delta: float = DEFAULT_DELTA) -> None:
        if not 0.0 < delta <= 1.0:
            raise ValueError(f"delta must be in (0, 1], got {delta}")
        self.delta = delta
        self._reset(0)

    def _reset(self, dim: int) -> None:
        self._u = np.empty((0, dim))
        self._pairs = np.empty((2, 1024), dtype=np.int32)  # (row, col) neighbour pairs, grown
        self._nnz = 0
        self.n = 0

    def update(self, u: np.ndarray) -> None:
        """Index normalised records u (n, dim); rows already indexed must be unchanged."""
        u = np.asarray(u, dtype=float)
        if u.ndim != 2:
            raise ValueError(f"expected normalised records of shape (n, dim), got {u.shape}")
        m = self.n
        if u.shape[1] != self._u.shape[1] or len(u) < m or not np.array_equal(u[:m], self._u[:m]):
            self._reset(u.shape[1])  # not an append: records were reordered or replaced
            m = 0
        n = len(u)
        for lo in range(m, n, _CHUNK_ROWS):
            hi = min(lo + _CHUNK_ROWS, n)
            near = cdist(u[lo:hi], u[:n], metric="chebyshev") <= self.delta  # (rows, n)
            rows, cols = np.nonzero(near)
            rows += lo
            old = cols < m  # a new–old pair is stored both ways; new–new pairs come from both rows
            self._add(np.concatenate([rows, cols[old]]), np.concatenate([cols, rows[old]]))
        self._u = u.copy()
        self.n = n

    def _add(self, rows: np.ndarray, cols: np.ndarray) -> None:
        end = self._nnz + len(rows)
        if end > self._pairs.shape[1]:  # grow by doubling: appends cost O(new pairs) amortised
            grown = np.empty((2, max(end, 2 * self._pairs.shape[1])), dtype=np.int32)
            grown[:, : self._nnz] = self._pairs[:, : self._nnz]
            self._pairs = grown
        self._pairs[0, self._nnz : end] = rows
        self._pairs[1, self._nnz : end] = cols
        self._nnz = end

    @property
    def n_pairs(self) -> int:
        """Σ |S_δ(x)| over the records (ordered pairs, self-pairs included)."""
        return self._nnz

    def neighbours(self, i: int) -> np.ndarray:
        """Indices of S_δ(x_i), including i itself, ascending."""
        rows, cols = self._pairs[:, : self._nnz]
        return np.sort(cols[rows == i])

    def potential(self, fbar: np.ndarray) -> np.ndarray:
        """q_δ (n,) = μ_δ + σ_δ of f̄ over each record's S_δ; unscored (NaN) records are skipped."""
        fbar = np.asarray(fbar, dtype=float)
        if fbar.shape != (self.n,):
            raise ValueError(f"expected {self.n} normalised feedback values, got {fbar.shape}")
        rows, cols = self._pairs[:, : self._nnz]
        adj = coo_array((np.ones(self._nnz), (rows, cols)), shape=(self.n, self.n))
        scored = np.isfinite(fbar)
        f0 = np.where(scored, fbar, 0.0)
        count, total, total_sq = (adj @ np.stack([scored, f0, f0 * f0], axis=1)).T  # (3, n)
        safe = np.maximum(count, 1.0)
        mu = total / safe
        sigma = np.sqrt(np.maximum(total_sq / safe - mu * mu, 0.0))  # population std
        return np.where(count > 0, mu + sigma, 0.0)


def regional_potential(u: np.ndarray, fbar: np.ndarray, delta: float = DEFAULT_DELTA) -> np.ndarray:
    """q_δ (n,) of every record from normalised params u (n, dim) and normalised feedback (n,)."""
    index = DensityIndex(delta)
    index.update(u)
    return index.potential(fbar)


def exploit_probability(q: np.ndarray, epsilon: float = EPSILON) -> np.ndarray:
    """p_δ = (q + ε) / (max q + ε), the max over all executed records."""
    q = np.asarray(q, dtype=float)
    return (q + epsilon) / (q.max() + epsilon)


def density_aware_mutation(
    space: LogicalScenario,
    x: np.ndarray,
    p_local: float,
    rng: np.random.Generator,
    delta: float = DEFAULT_DELTA,
) -> Mutation:
    """x' ~ Uniform(N_δ(x)) if ξ < p_local else Uniform(X), with ξ ~ Uniform(0, 1)."""
    local = bool(rng.random() < p_local)
    new = space.sample_near(x, rng, delta) if local else space.sample(rng)
    return Mutation(x=np.clip(new, space.low, space.high), local=local)  # clip: float round-off


class Potential(Protocol):
    """Region potential q per record, from normalised params u (n, dim) and f̄ (n,)."""

    def __call__(self, u: np.ndarray, fbar: np.ndarray) -> np.ndarray: ...


class NeighbourhoodPotential:
    """The paper's q_δ = μ_δ + σ_δ over S_δ, cached per (records, feedback) version."""

    def __init__(self, delta: float = DEFAULT_DELTA) -> None:
        self.index = DensityIndex(delta)
        self._key: tuple[int, bytes] | None = None
        self._q = np.empty(0)

    def __call__(self, u: np.ndarray, fbar: np.ndarray) -> np.ndarray:
        self.index.update(u)  # a no-op when no record was added
        key = (self.index.n, hashlib.blake2b(np.ascontiguousarray(fbar).tobytes()).digest())
        if key != self._key:
            self._q, self._key = self.index.potential(fbar), key
        return self._q


class SeedPotential:
    """Ablation "w/o density": S_δ(x) shrinks to {x}, so q(x) = f̄(x) (NaN counts as 0)."""

    def __call__(self, u: np.ndarray, fbar: np.ndarray) -> np.ndarray:
        return np.nan_to_num(np.asarray(fbar, dtype=float), nan=0.0)


class ConstantPotential:
    """Ablation "w/o feedback": no feedback signal, every q is equal, so every p_δ = 1."""

    def __call__(self, u: np.ndarray, fbar: np.ndarray) -> np.ndarray:
        return np.zeros(len(u))
