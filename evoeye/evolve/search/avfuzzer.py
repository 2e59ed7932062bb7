"""AV-Fuzzer (Li et al., ISSRE 2020) as an ask/tell acquisition baseline, per docs/avfuzzer.md.

A genetic algorithm over whole concrete scenarios, following the paper authors' own
re-implementation (Drivora `fuzzer/runner_avfuzzer.py`): population 4; each generation makes
len(pop)//2 crossover attempts (probability 0.6 each) that swap one actor's genes between two
distinct individuals, then mutates each individual with probability 0.6 by redrawing one gene of
one actor uniformly from its range; changed individuals are simulated; roulette selection with
weights max(0.001, 1 − fitness) draws the next population. Fitness is the run's criticality
(minimised). The best-so-far is kept aside. Restart: when 5 generations bring no improvement of
the best-so-far, keep it and resample the rest. Local iterative search (LIS): in every generation
from last_restart + 3 on, mutate copies of the best, then run 5 inner generations with mutation
probability 0.9; a result better than the best-so-far replaces the population's worst.

The GA is written as a generator that yields batches of scenarios and receives their fitness, so
the loop drives it one simulation at a time (`propose` / `tell`) and every run is charged to the
budget. Deviations from Drivora, each to avoid simulating a scenario whose result is known:
individuals a crossover left unchanged (both parents had the same genes for the swapped actor)
are not re-simulated, and neither is the best copy kept at a restart. The best-so-far is updated
on every simulated result, not only on the post-selection population. Where Drivora and
docs/avfuzzer.md differ, the specification wins: stagnation means the best-so-far at generation
g is no better than at g − 5 (Drivora compares the mean of the last 5 post-selection bests), and
LIS starts at generation last_restart + 3 (Drivora: + 4).
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass

import numpy as np

from evoeye.evolve.search.protocol import Proposal, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.scenarios import LogicalScenario

MIN_ROULETTE_WEIGHT = 0.001

Batch = tuple[np.ndarray, str]  # (k, dim) scenarios to simulate, and their proposal kind
Search = Generator[Batch, np.ndarray, None]


def actor_groups(space: LogicalScenario, exclude: tuple[str, ...] = ()) -> tuple[np.ndarray, ...]:
    """Parameter indices per actor (AV-Fuzzer's per-NPC gene groups), minus `exclude`."""
    unknown = set(exclude) - set(space.actors)
    if unknown:
        raise ValueError(f"{space.name}: unknown actors {sorted(unknown)}")
    groups = tuple(np.array(ix) for a, ix in space.actors.items() if a not in exclude)
    if not groups:
        raise ValueError(f"{space.name}: no gene group left to evolve")
    return groups


def crossover(
    pop: np.ndarray, groups: tuple[np.ndarray, ...], rng: np.random.Generator, p: float
) -> np.ndarray:
    """len(pop)//2 attempts; each, with probability p, swaps one actor's genes between two."""
    out = pop.copy()
    for _ in range(len(out) // 2):
        if rng.random() >= p:
            continue
        i, j = rng.choice(len(out), size=2, replace=False)
        g = groups[rng.integers(len(groups))]
        out[i, g], out[j, g] = out[j, g].copy(), out[i, g].copy()
    return out


def mutate(
    pop: np.ndarray,
    groups: tuple[np.ndarray, ...],
    low: np.ndarray,
    high: np.ndarray,
    rng: np.random.Generator,
    p: float,
) -> np.ndarray:
    """Each individual, with probability p: one gene of one actor redrawn uniformly in its range."""
    out = pop.copy()
    for i in range(len(out)):
        if rng.random() >= p:
            continue
        g = groups[rng.integers(len(groups))]
        k = g[rng.integers(len(g))]
        out[i, k] = rng.uniform(low[k], high[k])
    return out


def roulette_weights(fitness: np.ndarray) -> np.ndarray:
    """Selection probabilities ∝ max(0.001, 1 − fitness): the more critical, the likelier."""
    w = np.maximum(MIN_ROULETTE_WEIGHT, 1.0 - np.asarray(fitness, dtype=float))
    return w / w.sum()


def roulette_select(fitness: np.ndarray, rng: np.random.Generator, n: int) -> np.ndarray:
    """n indices drawn with replacement by roulette."""
    return rng.choice(len(fitness), size=n, replace=True, p=roulette_weights(fitness))


@dataclass(frozen=True)
class AVFuzzerConfig:
    population: int = 4
    p_crossover: float = 0.6
    p_mutation: float = 0.6
    stagnation_gens: int = 5  # restart after this many generations without improvement
    local_start_gens: int = 3  # LIS runs in every generation from last_restart + 3 on
    local_gens: int = 5  # inner generations of one LIS
    local_p_mutation: float = 0.9
    exclude_actors: tuple[str, ...] = ()  # e.g. ("ego",) to keep the ego's parameters fixed


@dataclass
class _Slot:
    x: np.ndarray
    kind: str
    proposed: bool = False
    fitness: float | None = None


class AVFuzzer:
    """AV-Fuzzer's GA, driven one simulation at a time; the ego is evolved like an NPC.

    Up to one batch (the changed individuals of a generation) can be proposed before any result
    is told; results may be told in any order. Inspect `generation`, `last_restart`, `best_x`,
    `best_fitness`, `population` and `population_fitness` for logging.
    """

    name = "avfuzzer"

    def __init__(
        self, space: LogicalScenario, seed: int, config: AVFuzzerConfig | None = None
    ) -> None:
        self.space = space
        self.seed = seed
        self.config = config or AVFuzzerConfig()
        self._groups = actor_groups(space, self.config.exclude_actors)
        self._rng = np.random.default_rng(seed)
        self.generation = 0
        self.last_restart = 0
        self.best_x: np.ndarray | None = None
        self.best_fitness = np.inf
        self.best_history: list[float] = []  # best-so-far at each generation's end, index = gen
        self.population = np.empty((0, space.dim))
        self.population_fitness = np.empty(0)
        self._search = self._run()
        self._slots = self._to_slots(next(self._search))

    # -- ask / tell ----------------------------------------------------------------------------
    def available(self) -> int:
        return sum(not s.proposed for s in self._slots)

    def propose(self, records: Records | None = None) -> Proposal:
        """The next scenario of the current batch; AV-Fuzzer does not read the records."""
        for s in self._slots:
            if not s.proposed:
                s.proposed = True
                return Proposal(x=s.x.copy(), kind=s.kind)
        raise StrategyError(
            f"avfuzzer: tell the results of the {len(self._slots)} scenarios in flight first"
        )

    def propose_ahead(self, records: Records | None, n: int) -> list[Proposal]:
        """Up to n of the generation's individuals not yet proposed: a generation's results
        are all told before the next is bred, and in any order."""
        return [self.propose() for _ in range(max(min(n, self.available()), 1))]

    def tell(self, x: np.ndarray, fitness: float) -> None:
        fitness = float(fitness)
        if not np.isfinite(fitness):
            raise StrategyError(f"avfuzzer: fitness must be finite, got {fitness}")
        slot = self._in_flight(np.asarray(x, dtype=float))
        if slot is None:
            raise StrategyError("avfuzzer: told a result for a scenario not in flight")
        slot.fitness = fitness
        if all(s.fitness is not None for s in self._slots):
            told = np.array([s.fitness for s in self._slots])
            self._slots = self._to_slots(self._search.send(told))

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        """Re-run the GA on its recorded results; lost in-flight runs are offered again."""
        params = np.asarray(params, dtype=float).reshape(-1, self.space.dim)
        fitness = np.asarray(fitness, dtype=float)
        if len(fitness) != len(params):
            raise ValueError(f"{len(params)} recorded runs but {len(fitness)} fitness values")
        for k, (x, f) in enumerate(zip(params, fitness, strict=True)):
            while self._in_flight(x) is None:
                if self.available() == 0:
                    raise StrategyError(
                        f"avfuzzer: cannot resume, recorded run {k} is not what this seed "
                        "proposes (another seed, another strategy, or a changed history)"
                    )
                self.propose()
            self.tell(x, f)
        for s in self._slots:  # in flight when the loop stopped: simulate them again
            if s.fitness is None:
                s.proposed = False

    def replay_results(self, fitness: np.ndarray) -> None:
        """Re-run the GA on results told in proposal order, whatever x each was simulated at
        (pool mode: the recorded runs are the pool rows nearest its proposals)."""
        for f in np.asarray(fitness, dtype=float):
            self.tell(self.propose().x, f)

    def _in_flight(self, x: np.ndarray) -> _Slot | None:
        for s in self._slots:
            if s.proposed and s.fitness is None and np.array_equal(s.x, x):
                return s
        return None

    @staticmethod
    def _to_slots(batch: Batch) -> list[_Slot]:
        xs, kind = batch
        return [_Slot(x=x.copy(), kind=kind) for x in xs]

    # -- the GA, as a generator of batches -------------------------------------------------------
    def _run(self) -> Search:
        cfg = self.config
        pop = self.space.sample(self._rng, cfg.population)
        fit = yield from self._evaluate(pop, "ga-init")
        self._keep(pop, fit)
        self.best_history.append(self.best_fitness)
        while True:
            self.generation += 1
            pop, fit = yield from self._generation(pop, fit, cfg.p_mutation, "ga")
            self._keep(pop, fit)
            self.best_history.append(self.best_fitness)
            if self._stagnant():
                pop, fit = yield from self._restart()
                self.last_restart = self.generation
                self._keep(pop, fit)
            if self.generation >= self.last_restart + cfg.local_start_gens:
                before = self.best_fitness
                yield from self._local_search()
                if self.best_fitness < before:
                    pop, fit = pop.copy(), fit.copy()
                    worst = int(np.argmax(fit))
                    pop[worst], fit[worst] = self.best_x, self.best_fitness
                    self._keep(pop, fit)

    def _evaluate(self, xs: np.ndarray, kind: str) -> Generator[Batch, np.ndarray, np.ndarray]:
        fit = np.asarray((yield xs, kind), dtype=float)
        for x, f in zip(xs, fit, strict=True):
            if f < self.best_fitness:
                self.best_x, self.best_fitness = x.copy(), float(f)
        return fit

    def _generation(
        self, pop: np.ndarray, fit: np.ndarray, p_mutation: float, kind: str
    ) -> Generator[Batch, np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """Crossover, mutation, simulate the changed individuals, roulette selection."""
        cfg, sp = self.config, self.space
        new = crossover(pop, self._groups, self._rng, cfg.p_crossover)
        new = mutate(new, self._groups, sp.low, sp.high, self._rng, p_mutation)
        changed = np.any(new != pop, axis=1)
        fit = fit.copy()
        if changed.any():
            fit[changed] = yield from self._evaluate(new[changed], kind)
        keep = roulette_select(fit, self._rng, len(new))
        return new[keep], fit[keep]

    def _restart(self) -> Generator[Batch, np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """Keep the best-so-far, resample the rest uniformly."""
        best_x, best_f = self.best_x.copy(), self.best_fitness
        fresh = self.space.sample(self._rng, self.config.population - 1)
        fit = yield from self._evaluate(fresh, "ga-restart")
        return np.vstack([best_x[None, :], fresh]), np.concatenate([[best_f], fit])

    def _local_search(self) -> Generator[Batch, np.ndarray, None]:
        """LIS: mutated copies of the best, then a few inner generations at high mutation rate."""
        cfg, sp = self.config, self.space
        pop = np.repeat(self.best_x[None, :], cfg.population, axis=0)
        pop = mutate(pop, self._groups, sp.low, sp.high, self._rng, 1.0)
        fit = yield from self._evaluate(pop, "ga-local")
        for _ in range(cfg.local_gens):
            pop, fit = yield from self._generation(pop, fit, cfg.local_p_mutation, "ga-local")

    def _stagnant(self) -> bool:
        g, k = self.generation, self.config.stagnation_gens
        return g - self.last_restart >= k and self.best_history[g] >= self.best_history[g - k]

    def _keep(self, pop: np.ndarray, fit: np.ndarray) -> None:
        self.population, self.population_fitness = pop.copy(), fit.copy()
