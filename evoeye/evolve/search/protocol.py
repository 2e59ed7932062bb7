"""The interface every acquisition strategy implements: ask for a scenario, tell its result.

A VerifAI-style split: the strategy proposes, the loop simulates and scores, the strategy hears
back. Every proposal is one run to simulate, so each is charged to the budget by the loop.

Resume contract: a strategy's state is rebuilt from its seed and the runs it already acquired
(`replay(params, fitness)`, in the order the loop recorded them); no other state is stored.
The density-aware strategies are stateless apart from a proposal counter (proposal k draws from
`default_rng([seed, k])` and reads the records passed in); AV-Fuzzer replays its told history
through its own deterministic generation logic.

Batches. The surrogate strategies (`boundary`, `disagreement`, the smoothed-feedback loops) fit
once per batch of `batch` proposals (the loop's N_round) and serve the batch from that fit.
Proposal k belongs to batch k // batch, chosen from the records as they were at its first
proposal: the first `records.n − k % batch` rows, since the loop records every proposal before
asking for the next. So a strategy resumed mid-batch rebuilds the same batch.

Pool mode (`evoeye.evolve.search.pool`): asked with `make_strategy(…, pool=rows)`, a strategy
picks rows of a finite (m, dim) array of already-simulated candidates instead of free θ; each
proposal's `pool_index` is its row, and no row is proposed twice or while it is in the records.

The loop, in outline (every proposal must be told and recorded, failed runs included):

    strategy = make_strategy(name, space, seed)
    strategy.replay(mine.params, mine.fitness)      # mine = records this strategy acquired
    while spent_s < budget_s:
        prop = strategy.propose(records)            # records = D_r, initial runs first
        ...simulate prop.x, score it with the current monitor...
        strategy.tell(prop.x, fitness)              # fitness = criticality(collided, gap_m)
        records = records.append(prop.x, feedback=..., fitness=..., ...)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from evoeye.evolve.search.records import Records


class StrategyError(RuntimeError):
    """A strategy asked to do something its state does not allow (or an unknown strategy)."""


@dataclass(frozen=True)
class Proposal:
    """One concrete scenario to simulate, and how the strategy came to it (for logs and plots)."""

    x: np.ndarray  # (dim,) in parameter units, inside the logical scenario's ranges
    kind: str  # "local" / "global" / "uniform" / "sobol" / "boundary" / "disagreement" / "ga…"
    parent: int | None = None  # row in the records of the seed that was mutated, if any
    p_local: float | None = None  # p_δ(seed) for the density-aware strategies
    pool_index: int | None = None  # pool mode: the row of the candidate pool x is
    # an importance-sampling strategy's exact densities at x, in parameter units: the
    # proposal's q and the scenario distribution's p (None: drawn as p, weight 1)
    log_q: float | None = None
    log_p: float | None = None


@runtime_checkable
class Strategy(Protocol):
    """An acquisition strategy over one logical scenario, seeded at construction."""

    name: str

    def propose(self, records: Records) -> Proposal:
        """The next scenario to simulate, given every executed record so far."""
        ...

    def tell(self, x: np.ndarray, fitness: float) -> None:
        """The result of simulating a proposed x: its criticality (minimised, in [0, 1])."""
        ...

    def available(self) -> int:
        """How many proposals can be made now before some results must be told."""
        ...

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        """Rebuild the state of a fresh strategy from the runs it acquired before (k, dim), (k,)."""
        ...
