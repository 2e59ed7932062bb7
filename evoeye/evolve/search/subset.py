"""`subset`: subset simulation over θ — find rare failures by conditioning level by level.

Subset simulation (Au & Beck, Prob. Eng. Mech. 2001) writes a rare event F as the last of
nested events F_1 ⊃ F_2 ⊃ … ⊃ F: a run is in F_i when its level (the record's fitness: for
the testing-efficiency protocol `risk_fitness`, 0 for a collision) is at most b_i. Each b_i is
chosen so that P(F_i | F_{i−1}) = p0, so a probability of 10⁻³ takes four or five levels of
conditional probabilities that are easy to estimate, instead of one that is not.

Levels on this protocol's batches. `batch` = c Markov chains; a level holds N = c / p0 samples.
* Level 0: N runs drawn from p (uniform on the box), c per batch.
* Level i ≥ 1: its seeds are the c samples of level i − 1 with the lowest level (ties: the
  earlier one), b_i the highest of theirs; each seed starts a chain and every chain takes
  1/p0 − 1 steps, one per batch (one run per chain). A step proposes, in standard-normal
  coordinates z = Φ⁻¹(u) of the normalised θ u (p is then a standard normal), the conditional
  sample ξ = ρ z + √(1 − ρ²) ε with ρ = √(1 − σ²) (Papaioannou et al., Prob. Eng. Mech. 2015:
  it leaves the standard normal invariant, so no Metropolis ratio is needed); the chain moves
  to the candidate if its run is in F_i, else stays. Level i's samples are its seeds and the
  chains' states after each step.
* σ adapts between levels towards an acceptance of 0.44 (σ ← σ·exp(acceptance − 0.44),
  within [SIGMA_MIN, 1]); every chain starts at SIGMA.
* Once a level holds at least c collisions, b is the failure itself: the chains keep walking
  inside F (every accepted step a further failure, of the same kind and its neighbours) and the
  estimate is frozen.

The estimate of P(F) (`subset_estimate`): p0^m · (the share of level m's samples that collided),
at the first level m holding c collisions, or else at the deepest level with a chain step
(or level 0, plain Monte Carlo). It is asymptotically unbiased (bias O(1/N)), with a
coefficient of variation that grows with the number of levels and the chains' correlation;
its runs carry no importance weight p/q: they are not draws of a known density (so they must
not be importance-weighted in training).

Why not openturns' `SubsetSampling`: it owns the sampling loop (it calls the model itself),
while a strategy here proposes a batch at a time, resumably; the algorithm is a few dozen
lines on scipy.stats.norm.

`subset-deep`: the same walk at p0 = 0.5, so every chain takes one step per level and a level
costs one batch (N = 2c). The cost of a factor e in probability is c (1/p0 − 1) / ln(1/p0)
runs: 25 at p0 = 0.2 and c = 10, 14 at p0 = 0.5. At P ≈ 10⁻³ with 200 runs, p0 = 0.2 spends its
budget reaching the fourth level (P(F_4) = 0.0016 at run 170), while p0 = 0.5 reaches 2⁻⁹ by
run 110 and walks inside F for the rest. The same estimator at p0 = 0.5 is near P on a clean
level (the tests' synthetic outcome) but not where the level is noisy (below): one step per
level leaves the chains no time to mix, a level's threshold falls with its luckiest runs rather
than with half its mass, and on the highway under the `defensive` stack its estimates were a
tenth of Uniform's. The rare-failure protocol takes no estimate from it.

`subset-spread`: `subset-deep` whose levels are taken over distinct runs, so a chain that
stayed put is one sample, not one per step. Where the level is noisy (on the highway under the
`defensive` stack a colliding θ collides again in about 1 of 8 runs with other run seeds, and a
safe run's peak risk of 30 falls to a median of 1.3), a lucky run drags the threshold below
anything its neighbours reach, its copies fill the next level's seeds and every chain parks on
it. Seeding from distinct runs keeps c chains on c different runs, and the walk enters F only
once c distinct runs collided. Its levels are no longer conditional probabilities of p0
either: it does not estimate P(F).

Determinism and resume. Every quantity above is a function of the strategy's own records (its
runs after the n_init there were at its first proposal) and of `default_rng([seed, b])` for
batch b, so a resumed strategy rebuilds every proposal. Generative mode only: a pool's finite
rows cannot host a chain's proposals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import norm

from evoeye.evolve.search.pool import CandidatePool
from evoeye.evolve.search.protocol import Proposal, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.strategies import BatchedStrategy
from evoeye.scenarios import LogicalScenario

P0 = 0.2  # the conditional probability of each level
P0_DEEP = 0.5  # `subset-deep`'s: a level per batch of chain steps
SIGMA = 0.6  # the conditional sampling's spread on the first level of chains
SIGMA_MIN = 0.1
TARGET_ACCEPT = 0.44
U_EDGE = 1e-9  # u is held this far inside (0, 1), so z = Φ⁻¹(u) stays finite


@dataclass
class Walk:
    """Subset simulation replayed over a strategy's own runs (module doc)."""

    chains: int
    p0: float
    distinct: bool = False  # seeds from distinct runs only (`subset-spread`: no estimate)
    level: int = 0
    final: bool = False  # the chains walk in F itself
    threshold: float = math.inf
    sigma: float = SIGMA
    states: list[int] = field(default_factory=list)  # each chain's current row
    samples: list[int] = field(default_factory=list)  # the current level's sample rows
    previous: list[int] = field(default_factory=list)  # the level before's, complete
    steps: int = 0  # chain steps taken on this level
    accepted: int = 0
    estimate: float | None = None  # frozen once `final`

    @property
    def steps_per_level(self) -> int:
        return max(int(round(1.0 / self.p0)) - 1, 1)

    @property
    def per_level(self) -> int:
        """N: samples per level, the seeds included."""
        return self.chains * (self.steps_per_level + 1)

    def reach(self, level: int) -> float:
        """P(F_level) as the estimator takes it: p0 per level (by construction; counting the
        ties a chain that stayed put adds at a threshold overestimated P by a third on the
        synthetic outcome of the tests). A running product, not p0 ** level: the bits every
        recorded estimate was computed with."""
        out = 1.0
        for _ in range(level):
            out *= self.p0
        return out

    @classmethod
    def replay(cls, fitness: np.ndarray, collided: np.ndarray, chains: int, p0: float,
               distinct: bool = False) -> Walk:
        """The walk after the runs (fitness, collided) (n,), in the order they were proposed
        (level 0's N, then whole batches of `chains`)."""
        w = cls(chains, p0, distinct)
        n, pos = len(fitness), w.per_level
        w.samples = list(range(min(n, pos)))
        if n < pos:
            return w
        w._new_level(fitness, collided)
        while pos + chains <= n:
            for j in range(chains):  # one step of every chain: candidates pos … pos + c − 1
                if w._inside(fitness[pos + j], collided[pos + j]):
                    w.states[j] = pos + j
                    w.accepted += 1
            w.samples.extend(w.states)
            w.steps += 1
            pos += chains
            if w.steps == w.steps_per_level:
                w._new_level(fitness, collided)
        return w

    def _inside(self, fitness: float, collided: bool) -> bool:
        if self.final:
            return bool(collided)
        return bool(np.isfinite(fitness) and fitness <= self.threshold)

    def _new_level(self, fitness: np.ndarray, collided: np.ndarray) -> None:
        """The next level from the current one's samples (complete): its seeds and threshold,
        or, once c of them collided, the walk inside F; σ from this level's acceptance."""
        rows = np.array(self.samples, dtype=np.int64)
        if self.distinct:  # a chain that stayed put counts once: ≥ c rows remain (level 0's
            # N are distinct, and every later level holds its c distinct seeds)
            rows = np.array(list(dict.fromkeys(self.samples)), dtype=np.int64)
        if self.steps:
            rate = self.accepted / (self.chains * self.steps)
            self.sigma = float(np.clip(self.sigma * math.exp(rate - TARGET_ACCEPT), SIGMA_MIN,
                                       1.0))
        if not self.final:
            hits = collided[rows]
            if np.count_nonzero(hits) >= self.chains:
                self.estimate = self.reach(self.level) * float(hits.mean())
                self.final = True
                self.states = [int(r) for r in rows[hits][: self.chains]]
            else:
                f = np.where(np.isfinite(fitness[rows]), fitness[rows], np.inf)
                order = np.lexsort((np.arange(len(rows)), f))[: self.chains]
                self.states = [int(r) for r in rows[order]]
                self.threshold = float(f[order].max())
        self.level += 1
        self.previous, self.samples = self.samples, list(self.states)
        self.steps = self.accepted = 0

    def estimate_now(self, collided: np.ndarray) -> float:
        """P(F) from the runs replayed (module doc)."""
        if self.estimate is not None:
            return self.estimate
        level, rows = self.level, self.samples
        if level > 0 and not self.steps:  # a level of seeds only: the one before is complete
            level, rows = level - 1, self.previous
        return self.reach(level) * float(collided[np.array(rows, dtype=np.int64)].mean())


def subset_estimate(fitness: np.ndarray, collided: np.ndarray, chains: int,
                    p0: float = P0) -> float:
    """P(F) from a `subset` strategy's runs in proposal order (module doc)."""
    fitness, collided = np.asarray(fitness, float), np.asarray(collided, bool)
    if not len(fitness):
        raise ValueError("no runs to estimate from")
    return Walk.replay(fitness, collided, chains, p0).estimate_now(collided)


class SubsetSimulation(BatchedStrategy):
    """Subset simulation with c = `batch` chains (module doc)."""

    name = "subset"
    distinct = False  # Walk.distinct

    def __init__(self, space: LogicalScenario, seed: int, batch: int = 20,
                 p0: float = P0) -> None:
        if not 0.0 < p0 <= 0.5:
            raise StrategyError(f"{self.name}: p0 must be in (0, 0.5], got {p0}")
        super().__init__(space, seed, batch)
        self.p0 = p0

    def _choose(self, records: Records, b: int, pool: CandidatePool | None) -> list[Proposal]:
        if pool is not None:
            raise StrategyError(f"{self.name}: generative mode only (a chain's proposals are "
                                "new points, not rows of a pool)")
        mine = records.tail(records.n - b * self.batch)  # its own runs
        w = Walk.replay(mine.fitness, mine.collided, self.batch, self.p0, self.distinct)
        rng = np.random.default_rng([self.seed, b])
        if b * self.batch < w.per_level:  # level 0: draws from p
            x = self.space.sample(rng, self.batch)
            return [Proposal(x=np.array(xi, dtype=float), kind="uniform") for xi in x]
        u = np.clip(self.space.normalise(mine.params[w.states]), U_EDGE, 1.0 - U_EDGE)
        rho = math.sqrt(1.0 - w.sigma**2)
        xi = rho * norm.ppf(u) + w.sigma * rng.standard_normal(u.shape)
        x = np.clip(self.space.denormalise(norm.cdf(xi)), self.space.low, self.space.high)
        return [Proposal(x=np.array(xi_, dtype=float), kind=self.name,
                         parent=records.n - b * self.batch + int(s))
                for xi_, s in zip(x, w.states, strict=True)]


class DeepSubsetSimulation(SubsetSimulation):
    """`subset-deep`: subset simulation at p0 = 0.5, a level per batch (module doc)."""

    name = "subset-deep"

    def __init__(self, space: LogicalScenario, seed: int, batch: int = 20,
                 p0: float = P0_DEEP) -> None:
        super().__init__(space, seed, batch, p0)


class SpreadSubsetSimulation(DeepSubsetSimulation):
    """`subset-spread`: `subset-deep` whose seeds are distinct runs (module doc); it does not
    estimate P(F)."""

    name = "subset-spread"
    distinct = True
