"""Where a curve's runs come from: the pre-simulated pool (screening) or the simulator
(confirmation), and the bank that holds every run's windows for training.

In pool mode a strategy picks a pool row (`Proposal.pool_index`) and the run is the pool's:
nothing is simulated. In generative mode the proposal's θ is simulated under the regime's ADS
profile with run seed k of the curve's seed (as a campaign seeds its runs), its log kept under
the regime's root (batch `gen-<strategy>-seed<seed>`), and its windows converted from the
Episode in memory; a log already on disk is read instead, so a killed curve resumes without
simulating a run twice. A run that failed is charged but has no windows.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from evoeye.batch import RunResult, simulate_and_keep_all
from evoeye.evolve.campaign.state import run_seed
from evoeye.evolve.search.fitness import criticality
from evoeye.evolve.search.protocol import Proposal
from evoeye.results.efficiency.config import parse_regime
from evoeye.results.efficiency.sets import RegimeData, RunTable, concat_windows
from evoeye.sim.episode import Episode, RunSpec
from evoeye.sim.runner import run_spec
from evoeye.store.log_windows import episode_run, read_logged_run
from evoeye.store.windows import Windows


@dataclass(frozen=True)
class AcquiredRun:
    """One acquired run: its θ and outcome (the Records columns)."""

    x: np.ndarray
    scenario_id: str
    fitness: float
    collided: bool
    duration_s: float


@dataclass
class Bank:
    """The windows of the pool's runs and of every run simulated since."""

    data: RegimeData
    extra: dict[str, Windows] = field(default_factory=dict)  # generated run → its windows

    @property
    def pool(self) -> RunTable:
        return self.data.pool

    def windows(self, ids: Sequence[str]) -> Windows:
        """The windows of these runs (pool runs as a view; with generated ones, a copy)."""
        ids = [str(s) for s in ids]
        if not any(s in self.extra for s in ids):
            return self.data.take(ids)
        pool = [s for s in ids if s not in self.extra]
        return concat_windows([self.data.take(pool), *(self.extra[s] for s in ids
                                                       if s in self.extra)])


class Acquirer:
    """Acquires a proposed run (pool mode: `PoolAcquirer`; generative: `SimAcquirer`)."""

    mode = ""
    pool_params: np.ndarray | None = None

    def acquire(self, prop: Proposal, seed: int, k: int) -> AcquiredRun:
        raise NotImplementedError

    def acquire_all(self, props: Sequence[Proposal], seed: int, k: int) -> list[AcquiredRun]:
        """`acquire` for proposals k, k + 1, … that wait on no outcome (`propose_ahead`)."""
        return [self.acquire(prop, seed, k + i) for i, prop in enumerate(props)]


class PoolAcquirer(Acquirer):
    """The proposal names a pool row: the run is the pool's."""

    mode = "pool"

    def __init__(self, bank: Bank) -> None:
        self.pool = bank.pool
        self.pool_params = bank.pool.params

    def acquire(self, prop: Proposal, seed: int, k: int) -> AcquiredRun:
        i = prop.pool_index
        if i is None:
            raise ValueError(f"a proposal of kind {prop.kind!r} names no pool row")
        p = self.pool
        return AcquiredRun(p.params[i].copy(), str(p.scenario_id[i]), float(p.fitness[i]),
                           bool(p.collided[i]), float(p.duration_s[i]))


class SimAcquirer(Acquirer):
    """The proposal's θ is simulated (module doc); its windows go into the bank."""

    mode = "generative"

    def __init__(self, bank: Bank, regime: str, strategy: str, context_len: int,
                 horizon_s: float) -> None:
        self.bank, self.strategy = bank, strategy
        self.scenario, self.profile = parse_regime(regime)
        self.context_len, self.horizon_s = context_len, horizon_s

    def _spec(self, prop: Proposal, seed: int, k: int) -> RunSpec:
        return run_spec(self.scenario, prop.x, run_seed(seed, k),
                        batch=f"gen-{self.strategy}-seed{seed}", source=self.strategy,
                        round=1 + k, ads=self.profile)

    def acquire(self, prop: Proposal, seed: int, k: int) -> AcquiredRun:
        return self.acquire_all([prop], seed, k)[0]

    def acquire_all(self, props: Sequence[Proposal], seed: int, k: int) -> list[AcquiredRun]:
        """The proposals' runs stepped together by the lockstep engine (the same runs)."""
        specs = [self._spec(prop, seed, k + i) for i, prop in enumerate(props)]
        return [self._acquired(spec, result, episode) for spec, (result, episode)
                in zip(specs, simulate_and_keep_all(specs, self.bank.data.data), strict=True)]

    def _acquired(self, spec: RunSpec, result: RunResult,
                  episode: Episode | None) -> AcquiredRun:
        if result.status == "error":
            raise RuntimeError(f"run {spec.scenario_id} could not be simulated: {result.reason}")
        run = (read_logged_run(result.path, self.context_len, self.horizon_s) if episode is None
               else episode_run(episode, result.path, self.context_len, self.horizon_s))
        if run.ok and run.windows is not None:
            self.bank.extra[spec.scenario_id] = run.windows
        gap = run.metadata.get("min_distance_m")
        collided = bool(run.metadata["collided"]) and run.ok
        return AcquiredRun(np.asarray(spec.params, float), spec.scenario_id,
                           float(criticality(collided, np.nan if gap is None else gap)),
                           collided, float(run.metadata["duration_s"]))
