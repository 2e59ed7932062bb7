"""The paper's acquisition strategies: BlindSpotEvolver, its two ablations, Uniform.

* `evoeye` — Algorithm 1, lines 6–7: a uniformly random seed from D_r, then density-aware
  mutation steered by the normalised monitor-oriented feedback of the δ-neighbourhood.
* `no-feedback` (paper RQ3 "w/o Feedback") — the same loop with the monitor-oriented feedback
  removed. Without a feedback signal every region potential q_δ is equal, so p_δ = 1 for every
  seed: each proposal is a uniform sample of N_δ around a uniformly random executed record.
* `no-density` (paper RQ3 "w/o Density") — the feedback is kept but the density awareness is
  removed: the potential of a seed is its own normalised feedback (S_δ(x) shrinks to {x}), so
  p(x) = (f̄(x) + ε) / (max_D f̄ + ε), regardless of how its neighbourhood was explored.
* `uniform` — uniform samples of X (the paper's Uniform baseline).
* `avfuzzer` — the GA of docs/avfuzzer.md, see `evoeye.evolve.search.avfuzzer`.

The strategies beyond the paper are in their own modules; `evoeye.evolve.search.registry` names
them all.

Proposal k of a density-aware or uniform strategy draws from `default_rng([seed, k])` only, so
the same seed, counter and records give the same proposal; `replay` just restores the counter.
"""

from __future__ import annotations

import sys
from collections.abc import Callable

import numpy as np

from evoeye.evolve.search.feedback import normalise_feedback
from evoeye.evolve.search.mutation import (
    EPSILON,
    Potential,
    density_aware_mutation,
    exploit_probability,
)
from evoeye.evolve.search.pool import CandidatePool
from evoeye.evolve.search.protocol import Proposal, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.scenarios import DEFAULT_DELTA, LogicalScenario


class CountedStrategy:
    """A strategy whose only state is how many proposals it made: proposal k uses rng([seed, k])."""

    name = ""

    def __init__(self, space: LogicalScenario, seed: int) -> None:
        self.space = space
        self.seed = seed
        self.proposals = 0

    def _next_rng(self) -> np.random.Generator:
        rng = np.random.default_rng([self.seed, self.proposals])
        self.proposals += 1
        return rng

    def tell(self, x: np.ndarray, fitness: float) -> None:
        """Nothing to learn: the feedback reaches these strategies through the records."""

    def available(self) -> int:
        return sys.maxsize

    def propose_ahead(self, records: Records, n: int) -> list[Proposal]:
        """Proposal k draws from rng([seed, k]) alone: all n (protocol.py, "Proposals ahead")."""
        return [self.propose(records) for _ in range(max(n, 1))]

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        self.proposals = len(np.asarray(params).reshape(-1, self.space.dim))


class UniformStrategy(CountedStrategy):
    """Uniform samples of the whole scenario space."""

    name = "uniform"

    def propose(self, records: Records | None = None) -> Proposal:
        return Proposal(x=self.space.sample(self._next_rng()), kind="uniform")

    def propose_in(self, records: Records, pool: CandidatePool, unused: np.ndarray) -> Proposal:
        """Pool mode: one of the unused rows, uniformly."""
        i = int(unused[self._next_rng().integers(len(unused))])
        return Proposal(x=pool.rows[i].copy(), kind="uniform", pool_index=i)


class DensityStrategy(CountedStrategy):
    """A random executed record as seed, mutated locally with probability p from its potential."""

    def __init__(
        self,
        space: LogicalScenario,
        seed: int,
        potential: Potential,
        name: str,
        delta: float = DEFAULT_DELTA,
        epsilon: float = EPSILON,
    ) -> None:
        super().__init__(space, seed)
        self.potential = potential
        self.name = name
        self.delta = delta
        self.epsilon = epsilon

    def exploit_probabilities(self, records: Records, k: int | None = None) -> np.ndarray:
        """p_δ (n,) of every executed record under the current feedback (`k`: the proposal
        they are for, which a batched potential needs)."""
        u = self.space.normalise(records.params)
        q = self.potential(u, normalise_feedback(records.feedback))
        return exploit_probability(q, self.epsilon)

    def propose_ahead(self, records: Records, n: int) -> list[Proposal]:
        """One: a proposal mutates a record, and the records grow with every run."""
        return [self.propose(records)]

    def propose(self, records: Records) -> Proposal:
        if records.n == 0:
            raise StrategyError(f"{self.name}: needs executed records (D_init) to pick seeds from")
        if records.params.shape[1] != self.space.dim:
            raise StrategyError(
                f"{self.name}: records have {records.params.shape[1]} parameters, "
                f"{self.space.name} has {self.space.dim}"
            )
        k = self.proposals
        rng = self._next_rng()
        p = self.exploit_probabilities(records, k)
        i = int(rng.integers(records.n))
        m = density_aware_mutation(self.space, records.params[i], p[i], rng, self.delta)
        return Proposal(x=m.x, kind="local" if m.local else "global", parent=i, p_local=float(p[i]))


def density_strategy(potential: Callable[[float], Potential],
                     name: str) -> Callable[..., DensityStrategy]:
    """The factory of a density-aware strategy whose potential is made from δ."""
    def make(
        space: LogicalScenario, seed: int, delta: float = DEFAULT_DELTA, epsilon: float = EPSILON
    ) -> DensityStrategy:
        return DensityStrategy(space, seed, potential(delta), name, delta, epsilon)

    return make


class BatchedStrategy(CountedStrategy):
    """A strategy that chooses a batch of `batch` proposals at a time from the records before
    it (protocol.py, "Batches"); subclasses define `_choose`."""

    name = ""

    def __init__(self, space: LogicalScenario, seed: int, batch: int = 20) -> None:
        if batch < 1:
            raise StrategyError(f"{self.name}: batch must be >= 1, got {batch}")
        super().__init__(space, seed)
        self.batch = batch
        self._served: tuple[int, list[Proposal]] | None = None  # (batch index, its proposals)

    def _choose(self, records: Records, b: int, pool: CandidatePool | None) -> list[Proposal]:
        """Batch b's proposals from `records`, the rows there were at its first proposal (in
        pool mode, among the rows they leave unused)."""
        raise NotImplementedError

    def propose(self, records: Records) -> Proposal:
        return self._serve(records, None)

    def propose_in(self, records: Records, pool: CandidatePool, unused: np.ndarray) -> Proposal:
        """Pool mode: the batch is chosen among the rows unused when it started."""
        return self._serve(records, pool)

    def propose_ahead(self, records: Records, n: int) -> list[Proposal]:
        """The next proposal and up to n − 1 more of its batch: the batch was chosen from the
        records at its start, so none of them reads the runs of the others."""
        out = [self._serve(records, None)]
        j = self.proposals % self.batch
        if j and self._served is not None:  # the batch goes on: serve its next ones as chosen
            more = self._served[1][j:j + max(n, 1) - 1]
            self.proposals += len(more)
            out += more
        return out

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        super().replay(params, fitness)
        self._served = None

    def _serve(self, records: Records, pool: CandidatePool | None) -> Proposal:
        if records.params.shape[1] != self.space.dim:
            raise StrategyError(f"{self.name}: records have {records.params.shape[1]} "
                                f"parameters, {self.space.name} has {self.space.dim}")
        b, j = divmod(self.proposals, self.batch)
        basis = records.n - j
        if basis < 0:
            raise StrategyError(f"{self.name}: {j} proposals of this batch but only "
                                f"{records.n} records (record every proposal)")
        if self._served is None or self._served[0] != b:
            self._served = (b, self._choose(records.head(basis), b, pool))
        served = self._served[1]
        if j >= len(served):
            raise StrategyError(f"{self.name}: the pool of {len(pool or ())} candidates is "
                                "used up")
        self.proposals += 1
        return served[j]

