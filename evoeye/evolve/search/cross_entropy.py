"""`ce-is`: cross-entropy adaptive importance sampling over θ, with exact weights p/q.

The scenario distribution p is uniform on the logical scenario's box (every batch of initial
runs is drawn from it), so on normalised θ u ∈ [0, 1]^d its density is 1. A run proposed by
this strategy is drawn from the defensive mixture

    q_b(u) = α · 1 + (1 − α) · g_b(u),    g_b = Π_d Beta(a_bd, b_bd)

of batch b (the loop's N_round proposals), so its importance weight p/q = 1 / q_b(u) is known
exactly, and bounded: p/q ≤ 1/α (Hesterberg's defensive mixture; α = 0.2 gives ≤ 5). Each
`Proposal` carries log q and log p in parameter units (the densities over θ, not u: both are
shifted by −Σ log span, so their ratio is that on u).

The cross-entropy update (Rubinstein & Kroese; O'Kelly et al., NeurIPS 2018, for AV testing).
Batch 0 is q = p (uniform: nothing is known yet). Batch b ≥ 1 fits g_b from the records before
it: every run, weighted by its p/q (D_init, drawn from p: 1; each of this strategy's runs: 1 /
q of the batch it was drawn from), and the elite among them — the collisions once they are at
least a share ρ of the runs, else the runs whose criticality (fitness, 0 for a collision) is at
most its ρ-quantile (multilevel CE: the level falls towards the failures as they are found).
Per dimension, g_b's Beta has the weighted mean and standard deviation of the elite's u (the
Beta's moments match exactly, so, unlike a truncated Gaussian fitted by its moments, a
dimension the failures do not depend on keeps its spread instead of shrinking every batch),
smoothed with the previous batch's (β·new + (1 − β)·old; the uniform is Beta(1, 1)), σ floored
at SIGMA_MIN, shapes held ≥ 1 (a finite density).

Screening. In the scenario spaces' 10–20 dimensions a few elite runs with unequal weights
always look narrow in some dimension by chance, and a proposal narrowed in dimensions the
failures do not depend on makes the weights degenerate (the curse of dimensionality of CE:
Au & Beck 2003). So a dimension adapts only where its weighted elite mean or variance departs
from p's (0.5, 1/12) by more than SCREEN_Z standard errors at the elite's effective size; the
others stay uniform.

Why scipy rather than openturns: openturns (which has CE-IS, NAIS and subset simulation) is not
installed here and would be a large compiled dependency for what is ≈ 40 lines on
`scipy.stats.beta`; its algorithms also own the sampling loop (they call the model
themselves), while a strategy here must propose one run at a time, resumably.

Determinism and resume. Batch b's draws come from `default_rng([seed, b])` and its proposal
from the records before it (the first n_init + b·batch rows; n_init = the records there were
when proposal 0 was asked), so a strategy resumed from its seed and the records (`replay`)
rebuilds every proposal, every density and every weight. `log_densities(records)` gives them for
records a campaign rebuilt from its tables.

Pool mode: a batch is drawn among the unused pool rows with probability ∝ q_b(u) (without
replacement); its log q is q_b's at the row. Weights p/q are exact for a pool as large as
the space's resolution, approximate for a finite pool (its rows are themselves a sample of p).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import beta

from evoeye.evolve.search.pool import CandidatePool
from evoeye.evolve.search.protocol import Proposal, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.strategies import BatchedStrategy
from evoeye.scenarios import LogicalScenario

ALPHA = 0.2  # the uniform's share of every proposal: p/q ≤ 1/ALPHA
RHO = 0.1  # the elite's share while collisions are fewer
SMOOTHING = 0.7  # β: the new fit's share of the proposal's μ and σ
SIGMA_MIN = 0.05  # floor of σ on normalised θ
MIN_RECORDS = 10  # fewer runs with a known outcome: the proposal stays as it was
MIN_ELITE = 2  # an elite needs a spread
SCREEN_Z = 3.0  # a dimension adapts when its elite moments are this many standard errors off p's
UNIFORM_SD = 1.0 / math.sqrt(12.0)  # p's σ on each normalised dimension
UNIFORM_VAR_SD = math.sqrt(1.0 / 80.0 - 1.0 / 144.0)  # the spread of one squared deviation


@dataclass(frozen=True)
class BetaProduct:
    """g(u) = Π_d Beta(a_d, b_d) on normalised θ, made from its mean and standard deviation
    per dimension (dim,) each: the Beta with exactly these moments, its shape parameters held
    at >= 1 (a density that stays finite at the box's edges)."""

    mean: np.ndarray
    sd: np.ndarray

    @property
    def shapes(self) -> tuple[np.ndarray, np.ndarray]:
        """(a, b) (dim,) each."""
        m = np.clip(self.mean, 1e-6, 1.0 - 1e-6)
        concentration = m * (1.0 - m) / self.sd**2 - 1.0
        a, b = m * concentration, (1.0 - m) * concentration
        return np.maximum(a, 1.0), np.maximum(b, 1.0)

    def logpdf(self, u: np.ndarray) -> np.ndarray:
        """(n,) log g of u (n, dim)."""
        a, b = self.shapes
        return beta.logpdf(np.atleast_2d(u), a, b).sum(axis=1)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """(n, dim) draws in [0, 1]."""
        a, b = self.shapes
        return rng.beta(a, b, size=(n, len(a)))

    def moments(self) -> tuple[np.ndarray, np.ndarray]:
        """(μ, σ) of the Beta actually used (its shapes clamped)."""
        a, b = self.shapes
        total = a + b
        return a / total, np.sqrt(a * b / (total**2 * (total + 1.0)))


@dataclass(frozen=True)
class DefensiveMixture:
    """q(u) = α + (1 − α) g(u) on the unit box; g None: q is the uniform p itself."""

    alpha: float
    proposal: BetaProduct | None = None

    def log_q(self, u: np.ndarray) -> np.ndarray:
        """(n,) log q of normalised θ (n, dim); 0 where q is uniform."""
        u = np.atleast_2d(u)
        if self.proposal is None:
            return np.zeros(len(u))
        return np.logaddexp(math.log(self.alpha),
                            math.log1p(-self.alpha) + self.proposal.logpdf(u))

    def sample(self, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(u (n, dim), from_proposal (n,) bool): each draw from g with probability 1 − α."""
        if self.proposal is None:
            raise StrategyError("a uniform mixture is sampled by the space")
        dim = len(self.proposal.mean)
        from_g = rng.random(n) >= self.alpha
        u = rng.uniform(0.0, 1.0, size=(n, dim))
        u[from_g] = self.proposal.sample(rng, int(from_g.sum()))
        return u, from_g

    def moments(self, dim: int) -> tuple[np.ndarray, np.ndarray]:
        """(μ, σ) the smoothing starts from: g's, or the uniform's."""
        if self.proposal is None:
            return np.full(dim, 0.5), np.full(dim, UNIFORM_SD)
        return self.proposal.moments()


def elite(fitness: np.ndarray, collided: np.ndarray, rho: float = RHO) -> np.ndarray:
    """(n,) bool: the collisions if they are at least a share ρ of the runs with a known
    fitness, else the runs whose fitness is at most its ρ-quantile (the collisions among them);
    NaN fitness is never elite."""
    known = np.isfinite(fitness)
    hit = collided & known
    if hit.sum() >= max(MIN_ELITE, math.ceil(rho * known.sum())):
        return hit
    level = np.quantile(fitness[known], rho) if known.any() else -np.inf
    return known & ((fitness <= level) | hit)


def effective_size(w: np.ndarray) -> float:
    """Kish's effective sample size (Σ w)² / Σ w² of weights w (n,)."""
    return float(w.sum() ** 2 / (w**2).sum())


def ce_update(previous: DefensiveMixture, u: np.ndarray, log_w: np.ndarray,
              fitness: np.ndarray, collided: np.ndarray, *, rho: float = RHO,
              smoothing: float = SMOOTHING, screen_z: float | None = None) -> DefensiveMixture:
    """The next mixture from runs u (n, dim) with log p/q (n,) and outcomes (module doc); the
    previous one while fewer than MIN_RECORDS outcomes or MIN_ELITE elite runs are known."""
    top = elite(fitness, collided, rho)
    if np.isfinite(fitness).sum() < MIN_RECORDS or top.sum() < MIN_ELITE:
        return previous
    w = np.exp(log_w[top] - log_w[top].max())
    w /= w.sum()
    mean = w @ u[top]
    var = w @ (u[top] - mean) ** 2
    # keep p's marginal where the elite's does not depart from it beyond sampling noise
    n_eff = effective_size(w)
    screen_z = SCREEN_Z if screen_z is None else screen_z  # read when called (tests patch it)
    moved = (np.abs(mean - 0.5) > screen_z * UNIFORM_SD / math.sqrt(n_eff)) | (
        UNIFORM_SD**2 - var > screen_z * UNIFORM_VAR_SD / math.sqrt(n_eff))
    mean = np.where(moved, mean, 0.5)
    sd = np.where(moved, np.sqrt(var), UNIFORM_SD)
    old_mean, old_sd = previous.moments(u.shape[1])
    mean = smoothing * mean + (1.0 - smoothing) * old_mean
    sd = np.maximum(smoothing * sd + (1.0 - smoothing) * old_sd, SIGMA_MIN)
    return DefensiveMixture(previous.alpha, BetaProduct(mean, sd))


class CrossEntropyIS(BatchedStrategy):
    """Cross-entropy adaptive importance sampling with a defensive mixture (module doc)."""

    name = "ce-is"

    def __init__(self, space: LogicalScenario, seed: int, batch: int = 20,
                 alpha: float = ALPHA, rho: float = RHO, screen_z: float | None = None) -> None:
        if not 0.0 < alpha <= 1.0:
            raise StrategyError(f"{self.name}: alpha must be in (0, 1], got {alpha}")
        if not 0.0 < rho < 1.0:
            raise StrategyError(f"{self.name}: rho must be in (0, 1), got {rho}")
        if screen_z is not None and not screen_z >= 0.0:
            raise StrategyError(f"{self.name}: screen_z must be >= 0, got {screen_z}")
        super().__init__(space, seed, batch)
        self.alpha, self.rho, self.screen_z = alpha, rho, screen_z
        self.log_span = float(np.log(space.high - space.low).sum())  # u → θ: density / Π span
        self._mixtures: list[DefensiveMixture] = []  # per batch, rebuilt from the records

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        super().replay(params, fitness)
        self._mixtures = []

    # -- densities -------------------------------------------------------------------------------
    def mixture(self, b: int, records: Records, n_init: int) -> DefensiveMixture:
        """q of batch b, fitted from the first n_init + b·batch records (memoised)."""
        while len(self._mixtures) <= b:
            k = len(self._mixtures)
            if k == 0:
                self._mixtures.append(DefensiveMixture(self.alpha))
                continue
            basis = records.head(n_init + k * self.batch)
            u = self.space.normalise(basis.params)
            log_w = -self._log_q_unit(u, n_init)
            self._mixtures.append(ce_update(self._mixtures[-1], u, log_w, basis.fitness,
                                            basis.collided, rho=self.rho,
                                            screen_z=self.screen_z))
        return self._mixtures[b]

    def _log_q_unit(self, u: np.ndarray, n_init: int) -> np.ndarray:
        """(n,) log q on the unit box of each record's own proposal (0 for D_init: drawn from
        p), from the mixtures built so far (they must cover every acquired row)."""
        out = np.zeros(len(u))
        for i in range(n_init, len(u)):
            out[i] = self._mixtures[(i - n_init) // self.batch].log_q(u[i])[0]
        return out

    def log_densities(self, records: Records, n_init: int) -> tuple[np.ndarray, np.ndarray]:
        """(log q, log p) (n,) in parameter units of every record acquired by this strategy
        after the first n_init (NaN for those: they carry no proposal of this strategy)."""
        acquired = records.n - n_init
        if acquired < 0:
            raise StrategyError(f"{self.name}: {n_init} initial rows but {records.n} records")
        if acquired:
            self.mixture((acquired - 1) // self.batch, records, n_init)
        log_q = self._log_q_unit(self.space.normalise(records.params), n_init) - self.log_span
        log_q[:n_init] = np.nan
        log_p = np.where(np.isnan(log_q), np.nan, -self.log_span)
        return log_q, log_p

    # -- batches ---------------------------------------------------------------------------------
    def _choose(self, records: Records, b: int, pool: CandidatePool | None) -> list[Proposal]:
        n_init = records.n - b * self.batch  # `records`: D_init and batches 0 .. b − 1
        if n_init < 0:
            raise StrategyError(f"{self.name}: batch {b} but only {records.n} records "
                                "(record every proposal)")
        return self._draw(b, self.mixture(b, records, n_init), records, pool)

    def _draw(self, b: int, q: DefensiveMixture, basis: Records,
              pool: CandidatePool | None) -> list[Proposal]:
        """Batch b's proposals from q, in pool mode among the rows `basis` (the records before
        the batch) leaves unused."""
        rng = np.random.default_rng([self.seed, b])
        if pool is not None:
            rows = pool.unused(basis)
            log_q = q.log_q(pool.u[rows])
            p = np.exp(log_q - log_q.max())
            n = min(self.batch, len(rows))
            picks = rng.choice(len(rows), size=n, replace=False, p=p / p.sum())
            return [self._proposal(pool.rows[rows[i]], log_q[i], q.proposal is not None,
                                   int(rows[i])) for i in picks]
        if q.proposal is None:
            u, from_g = rng.uniform(0.0, 1.0, size=(self.batch, self.space.dim)), None
        else:
            u, from_g = q.sample(rng, self.batch)
        x = np.clip(self.space.denormalise(u), self.space.low, self.space.high)
        log_q = q.log_q(self.space.normalise(x))  # of θ as recorded: recomputed bit for bit
        return [self._proposal(x[i], log_q[i], from_g is not None and bool(from_g[i]))
                for i in range(self.batch)]

    def _proposal(self, x: np.ndarray, log_q_unit: float, from_g: bool,
                  pool_index: int | None = None) -> Proposal:
        return Proposal(x=np.array(x, dtype=float), kind=self.name if from_g else "uniform",
                        pool_index=pool_index, log_q=float(log_q_unit) - self.log_span,
                        log_p=-self.log_span)
