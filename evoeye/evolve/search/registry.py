"""Acquisition strategies by name: the registry every command and campaign picks from.

* the paper's: `evoeye` (BlindSpotEvolver), its ablations `no-feedback` and `no-density`,
  `uniform` (`strategies.py`) and `avfuzzer` (`avfuzzer.py`);
* beyond the paper: `sobol` (low-discrepancy Uniform, `sobol.py`), `boundary` (level-set
  sampling of the safety margin, `boundary.py`), `disagreement` (where a committee of monitors
  disagrees, `disagreement.py`), and `evoeye-knn` / `evoeye-forest` (the paper's loop with a
  smoothed feedback potential, `smoothed.py`), and `ce-is` (cross-entropy adaptive importance
  sampling with a defensive mixture: exact weights p/q for rare events, `cross_entropy.py`) and
  `subset` (subset simulation: Markov chains conditioned level by level towards the failures,
  `subset.py`), and `subset-deep` (the same at p0 = 0.5: a level per batch, deeper in the
  same budget), and `subset-spread` (`subset-deep` seeded from distinct runs only).

`make_strategy(…, pool=rows)` restricts any of them to a finite pool of candidates (`pool.py`).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import numpy as np

from evoeye.evolve.search.avfuzzer import AVFuzzer
from evoeye.evolve.search.boundary import BoundaryStrategy
from evoeye.evolve.search.cross_entropy import CrossEntropyIS
from evoeye.evolve.search.disagreement import DisagreementStrategy
from evoeye.evolve.search.mutation import ConstantPotential, NeighbourhoodPotential, SeedPotential
from evoeye.evolve.search.pool import CandidatePool, PooledStrategy
from evoeye.evolve.search.protocol import Strategy, StrategyError
from evoeye.evolve.search.smoothed import smoothed
from evoeye.evolve.search.sobol import SobolStrategy
from evoeye.evolve.search.strategies import UniformStrategy, density_strategy
from evoeye.evolve.search.subset import (
    DeepSubsetSimulation,
    SpreadSubsetSimulation,
    SubsetSimulation,
)
from evoeye.scenarios import LogicalScenario

StrategyFactory = Callable[..., Strategy]

STRATEGIES: dict[str, StrategyFactory] = {
    "evoeye": density_strategy(NeighbourhoodPotential, "evoeye"),
    "no-feedback": density_strategy(lambda _delta: ConstantPotential(), "no-feedback"),
    "no-density": density_strategy(lambda _delta: SeedPotential(), "no-density"),
    "uniform": UniformStrategy,
    "avfuzzer": AVFuzzer,
    "sobol": SobolStrategy,
    "boundary": BoundaryStrategy,
    "disagreement": DisagreementStrategy,
    "evoeye-knn": smoothed("evoeye-knn"),
    "evoeye-forest": smoothed("evoeye-forest"),
    "ce-is": CrossEntropyIS,
    "subset": SubsetSimulation,
    "subset-deep": DeepSubsetSimulation,
    "subset-spread": SpreadSubsetSimulation,
}
# Strategies whose proposals never read the records' feedback: the feedback mode cannot change
# what they acquire (the monitor updates are the same too), so it is not part of their identity.
# (`disagreement` reads the committee's scores, which the feedback mode rescales.)
FEEDBACK_BLIND = frozenset({"uniform", "avfuzzer", "no-feedback", "sobol", "boundary",
                            "ce-is", "subset", "subset-deep", "subset-spread"})
# Strategies that propose new points only: a pool's finite rows cannot host them.
GENERATIVE_ONLY = frozenset({"subset", "subset-deep", "subset-spread"})
# Strategies whose records need the committee's disagreement (`Records.disagreement`).
READS_DISAGREEMENT = frozenset({"disagreement"})


def make_strategy(name: str, space: LogicalScenario, seed: int, *,
                  pool: np.ndarray | None = None, **options: Any) -> Strategy:
    """The strategy called `name` over `space`, seeded; options go to its factory. With `pool`
    (m, dim) in parameter units, it picks rows of that pool (`evoeye.evolve.search.pool`)."""
    try:
        factory = STRATEGIES[name]
    except KeyError:
        raise StrategyError(
            f"unknown acquisition strategy {name!r}; known: {sorted(STRATEGIES)}"
        ) from None
    strategy = factory(space, seed, **options)
    return strategy if pool is None else PooledStrategy(strategy, CandidatePool(space, pool))


def strategy_options(name: str, **given: Any) -> dict[str, Any]:
    """The options of `given` that strategy `name`'s factory takes (e.g. `delta` for the
    density-aware ones, `batch` for the batched ones)."""
    accepted = inspect.signature(STRATEGIES[name]).parameters
    return {k: v for k, v in given.items() if k in accepted}
