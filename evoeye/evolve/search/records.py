"""The executed scenario records D that acquisition strategies read (one row per simulated run)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np


@dataclass(frozen=True)
class Records:
    """D in acquisition order: vectors, feedback and outcomes; append-only, rows never reordered.

    Only `params` and `feedback` steer the density-aware strategies; the other columns are what
    the loop needs anyway (AV-Fuzzer fitness, collisions, the simulated time charged), and
    `disagreement`, which only the `disagreement` strategy reads: how much K monitors disagree
    on the run (mean over its contexts of the spread of their scores), NaN where unknown;
    `log_q` and `log_p`, the densities of the proposal a run was drawn from and of the scenario
    distribution at its θ (an importance-sampling strategy's, `Proposal.log_q`), NaN for a run
    drawn from p itself: its weight p/q is 1 (`importance_ratio`).
    """

    params: np.ndarray  # (n, dim) concrete scenarios, parameter units
    feedback: np.ndarray  # (n,) f_r(x) under the current monitor; NaN = not scored
    fitness: np.ndarray | None = None  # (n,) criticality in [0, 1], minimised; NaN = unknown
    collided: np.ndarray | None = None  # (n,) bool
    duration_s: np.ndarray | None = None  # (n,) simulated seconds of each run
    scenario_id: np.ndarray | None = None  # (n,) str, to align refreshed feedback with the runs
    disagreement: np.ndarray | None = None  # (n,) spread of K monitors' scores; NaN = unknown
    log_q: np.ndarray | None = None  # (n,) log density of the run's proposal; NaN = p itself
    log_p: np.ndarray | None = None  # (n,) log density of p at the run's θ; NaN = as log_q

    def __post_init__(self) -> None:
        params = np.asarray(self.params, dtype=float)
        if params.ndim != 2:
            raise ValueError(f"params must be (n, dim), got shape {params.shape}")
        n = len(params)
        cols = {
            "params": params,
            "feedback": _column(self.feedback, n, np.nan, float, "feedback"),
            "fitness": _column(self.fitness, n, np.nan, float, "fitness"),
            "collided": _column(self.collided, n, False, bool, "collided"),
            "duration_s": _column(self.duration_s, n, 0.0, float, "duration_s"),
            "scenario_id": _column(self.scenario_id, n, "", object, "scenario_id"),
            "disagreement": _column(self.disagreement, n, np.nan, float, "disagreement"),
            "log_q": _column(self.log_q, n, np.nan, float, "log_q"),
            "log_p": _column(self.log_p, n, np.nan, float, "log_p"),
        }
        for name, value in cols.items():
            object.__setattr__(self, name, value)

    @classmethod
    def empty(cls, dim: int) -> Records:
        return cls(params=np.empty((0, dim)), feedback=np.empty(0))

    @property
    def n(self) -> int:
        return len(self.params)

    def __len__(self) -> int:
        return self.n

    def append(
        self,
        x: np.ndarray,
        *,
        feedback: float = np.nan,
        fitness: float = np.nan,
        collided: bool = False,
        duration_s: float = 0.0,
        scenario_id: str = "",
        disagreement: float = np.nan,
        log_q: float | None = None,
        log_p: float | None = None,
    ) -> Records:
        """A new table with one more run at the end (O(n) copy; n is a few thousand at most)."""
        return Records(
            params=np.vstack([self.params, np.asarray(x, dtype=float)[None, :]]),
            feedback=np.append(self.feedback, feedback),
            fitness=np.append(self.fitness, fitness),
            collided=np.append(self.collided, collided),
            duration_s=np.append(self.duration_s, duration_s),
            scenario_id=np.append(self.scenario_id, np.array([scenario_id], dtype=object)),
            disagreement=np.append(self.disagreement, disagreement),
            log_q=np.append(self.log_q, np.nan if log_q is None else log_q),
            log_p=np.append(self.log_p, np.nan if log_p is None else log_p),
        )

    def importance_ratio(self) -> np.ndarray:
        """(n,) p/q of every run: exp(log_p − log_q), 1 where no proposal density is known."""
        known = np.isfinite(self.log_q) & np.isfinite(self.log_p)
        return np.where(known, np.exp(np.where(known, self.log_p - self.log_q, 0.0)), 1.0)

    def ratio_by_run(self) -> dict[str, float]:
        """scenario_id → p/q (`importance_ratio`) of every run."""
        return dict(zip(map(str, self.scenario_id), self.importance_ratio().tolist(),
                        strict=True))

    def with_feedback(self, feedback: np.ndarray) -> Records:
        """The same runs with every feedback refreshed (after a monitor update)."""
        return replace(self, feedback=np.asarray(feedback, dtype=float))

    def with_disagreement(self, disagreement: np.ndarray) -> Records:
        """The same runs with every disagreement refreshed (after the monitors' update)."""
        return replace(self, disagreement=np.asarray(disagreement, dtype=float))

    def with_densities(self, log_q: np.ndarray, log_p: np.ndarray) -> Records:
        """The same runs with their proposal densities (e.g. recomputed on resume)."""
        return replace(self, log_q=np.asarray(log_q, dtype=float),
                       log_p=np.asarray(log_p, dtype=float))

    def tail(self, start: int) -> Records:
        """Rows from `start` on, e.g. the records one strategy acquired after D_init."""
        return self._rows(slice(start, None))

    def head(self, stop: int) -> Records:
        """The first `stop` rows, e.g. the records a batch of proposals was chosen from."""
        return self._rows(slice(0, stop))

    def _rows(self, rows: slice) -> Records:
        return Records(**{f.name: getattr(self, f.name)[rows] for f in fields(self)})


def _column(value, n: int, default, dtype, name: str) -> np.ndarray:
    if value is None:
        return np.full(n, default, dtype=dtype)
    arr = np.asarray(value, dtype=dtype)
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {arr.shape}")
    return arr
