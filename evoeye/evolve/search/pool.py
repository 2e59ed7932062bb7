"""Pool mode: a strategy picks rows of a finite set of already-simulated candidates.

Pool-based screening compares strategies without simulating: every run is taken from a pool of
pre-simulated uniform runs, so a strategy must choose among the pool's rows instead of proposing
free θ. `make_strategy(name, space, seed, pool=rows)` wraps any strategy so:

* a strategy that can score candidates (`propose_in`: uniform, the surrogates) picks among the
  pool's unused rows itself — uniform draws one uniformly, a surrogate scores them;
* every other one (the paper's loop and its ablations, AV-Fuzzer, Sobol, the smoothed-feedback
  loops) proposes as usual and its proposal is snapped to the nearest unused row (Euclidean on
  normalised θ); AV-Fuzzer is told its result against the x it proposed.

A row is *unused* while no record has its exact params and no proposal of it is in flight
(proposed, not told yet), so D_init may come from the pool too. Each `Proposal` carries its
`pool_index`. The state is rebuilt from the seed and the records, as outside pool mode
(`replay`); a strategy that only hears results (AV-Fuzzer) is replayed by proposing again in
order (`replay_results`), since its recorded runs are snapped rows, not its own proposals.

    strategy = make_strategy("boundary", space, seed=3, pool=pool_params)   # (m, dim)
    prop = strategy.propose(records)
    i = prop.pool_index                                # the pre-simulated run to take
    records = records.append(pool_params[i], fitness=fitness[i], collided=collided[i])
    strategy.tell(pool_params[i], fitness[i])
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from evoeye.evolve.search.protocol import Proposal, Strategy, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.scenarios import LogicalScenario


class CandidatePool:
    """m concrete scenarios (m, dim) in parameter units, looked up by their exact params."""

    def __init__(self, space: LogicalScenario, rows: np.ndarray) -> None:
        rows = np.array(rows, dtype=float)  # a copy: the pool must not change under the strategy
        if rows.ndim != 2 or rows.shape[1] != space.dim or len(rows) == 0:
            raise StrategyError(f"a pool of {space.name} must be a non-empty (m, {space.dim}) "
                                f"array, got shape {rows.shape}")
        outside = ~((rows >= space.low) & (rows <= space.high)).all(axis=1)
        if outside.any():
            raise StrategyError(f"pool row {int(np.argmax(outside))} is outside the ranges of "
                                f"{space.name}")
        self.space = space
        self.rows = rows
        self.u = space.normalise(rows)  # (m, dim) in [0, 1]
        self._index: dict[bytes, int] = {}
        for i, row in enumerate(rows):
            self._index.setdefault(row.tobytes(), i)

    def __len__(self) -> int:
        return len(self.rows)

    def index_of(self, x: np.ndarray) -> int | None:
        """The row whose params are exactly x (the first, if repeated), or None."""
        return self._index.get(np.asarray(x, dtype=float).tobytes())

    def unused(self, records: Records | None,
               in_flight: frozenset[int] = frozenset()) -> np.ndarray:
        """Indices (ascending) of the rows no record holds and none of `in_flight`."""
        free = np.ones(len(self), dtype=bool)
        for x in () if records is None else records.params:
            i = self.index_of(x)
            if i is not None:
                free[i] = False
        free[list(in_flight)] = False
        return np.flatnonzero(free)

    def nearest(self, x: np.ndarray, among: np.ndarray) -> int:
        """The row of `among` nearest x (Euclidean on normalised θ; ties: the lowest index)."""
        d2 = ((self.u[among] - self.space.normalise(x)) ** 2).sum(axis=1)
        return int(among[int(np.argmin(d2))])


class PooledStrategy:
    """A strategy restricted to the rows of a pool (see the module docstring)."""

    def __init__(self, inner: Strategy, pool: CandidatePool) -> None:
        self.inner = inner
        self.pool = pool
        self.name = inner.name
        self._in_flight: dict[int, np.ndarray] = {}  # row → the x the inner strategy proposed

    def propose(self, records: Records) -> Proposal:
        unused = self.pool.unused(records, frozenset(self._in_flight))
        if len(unused) == 0:
            raise StrategyError(f"{self.name}: the pool of {len(self.pool)} candidates is used up")
        pick = getattr(self.inner, "propose_in", None)
        if pick is not None:
            prop = pick(records, self.pool, unused)
            inner_x = prop.x
        else:
            inner = self.inner.propose(records)
            i = self.pool.nearest(inner.x, unused)
            prop, inner_x = replace(inner, x=self.pool.rows[i].copy(), pool_index=i), inner.x
        if prop.pool_index not in set(unused.tolist()):
            raise StrategyError(f"{self.name}: picked pool row {prop.pool_index}, which is used")
        self._in_flight[prop.pool_index] = inner_x
        return prop

    def tell(self, x: np.ndarray, fitness: float) -> None:
        i = self.pool.index_of(x)
        if i is None or i not in self._in_flight:
            raise StrategyError(f"{self.name}: told a result for a pool row not in flight")
        self.inner.tell(self._in_flight.pop(i), fitness)

    def available(self) -> int:
        return self.inner.available()

    def propose_ahead(self, records: Records, n: int) -> list[Proposal]:
        """One: pool mode simulates nothing, and a pick must see the rows the last one took."""
        return [self.propose(records)]

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        """Rebuild from the pool rows this strategy acquired (k, dim) and their fitness (k,)."""
        self._in_flight.clear()
        again = getattr(self.inner, "replay_results", None)
        if again is not None:
            again(np.asarray(fitness, dtype=float))
        else:
            self.inner.replay(params, fitness)
