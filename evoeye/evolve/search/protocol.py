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

Proposals ahead (optional). A strategy's `propose_ahead(records, n)` gives the next 1 to n
proposals that do not depend on each other's outcome, all at once: every one for Uniform and
Sobol', the rest of the current batch for the batched strategies, the individuals in flight for
AV-Fuzzer, one for the density-aware strategies (each reads the records of the one before). A
loop that simulates them together and then tells and records them in order acquires exactly
what the outline below does. A strategy without the method (a plug-in's) is asked one proposal
at a time (`propose_ahead`).

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


def propose_ahead(strategy: Strategy, records: Records, n: int) -> list[Proposal]:
    """The next 1 to n proposals of `strategy` that neither the records nor the results of the
    ones before them can change (module doc, "Proposals ahead"): a loop may simulate them
    together, then tell and record them in order. One for a strategy that cannot say."""
    ahead = getattr(strategy, "propose_ahead", None)
    return ahead(records, n) if ahead is not None else [strategy.propose(records)]
