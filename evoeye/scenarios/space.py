"""Logical scenario spaces: named, bounded parameter lists and the geometry on them.

A *logical scenario* is a list of parameters with ranges; a *concrete scenario* is one vector in
it. All geometry (distance, neighbourhoods) is measured on parameters normalised to [0, 1], so a
metre and a second weigh the same (paper §II-B, §IV-C).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from evoeye.lazy import LazyModule

if TYPE_CHECKING:
    import numpy as np
else:  # numpy on first use: the registry of scenarios is read by `evoeye --help`
    np = LazyModule("numpy")

DEFAULT_DELTA = 0.2  # neighbourhood radius, as a share of each parameter's range


class ScenarioError(ValueError):
    """A concrete scenario that does not belong to its logical scenario."""


@dataclass(frozen=True, slots=True)
class Parameter:
    """One scenario parameter: name, closed range [low, high], unit, a one-line meaning, and the
    actor it belongs to (AV-Fuzzer's genes are grouped by actor)."""

    name: str
    low: float
    high: float
    unit: str
    meaning: str
    actor: str = ""

    def __post_init__(self) -> None:
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low < self.high):
            raise ScenarioError(f"parameter {self.name!r}: need finite low < high")

    @property
    def span(self) -> float:
        return self.high - self.low


@dataclass(frozen=True)
class LogicalScenario:
    """A named parameter space; concrete scenarios are float vectors in parameter order."""

    name: str
    description: str
    parameters: tuple[Parameter, ...]
    _index: dict[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ScenarioError(f"{self.name}: duplicate parameter names")
        object.__setattr__(self, "_index", {n: i for i, n in enumerate(names)})

    # -- shape -------------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return len(self.parameters)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def low(self) -> np.ndarray:
        return np.array([p.low for p in self.parameters])

    @property
    def high(self) -> np.ndarray:
        return np.array([p.high for p in self.parameters])

    def index(self, name: str) -> int:
        return self._index[name]

    @property
    def actors(self) -> dict[str, tuple[int, ...]]:
        """Parameter indices per actor, in declaration order (e.g. {"lead": (1, 2, …), …})."""
        out: dict[str, list[int]] = {}
        for i, p in enumerate(self.parameters):
            out.setdefault(p.actor, []).append(i)
        return {a: tuple(ix) for a, ix in out.items()}

    # -- validation --------------------------------------------------------------------------
    def validate(self, x: Sequence[float] | np.ndarray) -> np.ndarray:
        """Return x as a float array, or raise ScenarioError naming the offending parameter."""
        arr = np.asarray(x, dtype=float)
        if arr.ndim != 1 or arr.shape[0] != self.dim:
            raise ScenarioError(
                f"{self.name}: expected a vector of {self.dim} parameters, got shape {arr.shape}"
            )
        for p, v in zip(self.parameters, arr, strict=True):
            if not math.isfinite(v) or v < p.low or v > p.high:
                raise ScenarioError(
                    f"{self.name}: parameter {p.name!r} = {v} is outside "
                    f"[{p.low}, {p.high}] {p.unit}"
                )
        return arr

    def as_dict(self, x: Sequence[float] | np.ndarray) -> dict[str, float]:
        arr = self.validate(x)
        return {n: float(v) for n, v in zip(self.names, arr, strict=True)}

    def from_dict(self, values: dict[str, float]) -> np.ndarray:
        missing = [n for n in self.names if n not in values]
        extra = [k for k in values if k not in self._index]
        if missing or extra:
            raise ScenarioError(f"{self.name}: missing {missing}, unknown {extra}")
        return self.validate([values[n] for n in self.names])

    # -- geometry ----------------------------------------------------------------------------
    def normalise(self, x: np.ndarray) -> np.ndarray:
        """Map vectors (..., dim) to [0, 1] per parameter."""
        return (np.asarray(x, dtype=float) - self.low) / (self.high - self.low)

    def denormalise(self, u: np.ndarray) -> np.ndarray:
        return self.low + np.asarray(u, dtype=float) * (self.high - self.low)

    def distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Chebyshev distance on normalised parameters, broadcasting over leading axes.

        Chebyshev (max-norm) makes N_δ(x) exactly the box of half-width δ·range around x, so
        "distance ≤ δ" and "uniform sample inside N_δ" describe the same set.
        """
        return np.max(np.abs(self.normalise(a) - self.normalise(b)), axis=-1)

    def sample(self, rng: np.random.Generator, n: int | None = None) -> np.ndarray:
        """Uniform samples of the whole space: (dim,) or (n, dim)."""
        size = (self.dim,) if n is None else (n, self.dim)
        return self.denormalise(rng.uniform(0.0, 1.0, size=size))

    def sample_near(
        self, x: np.ndarray, rng: np.random.Generator, delta: float = DEFAULT_DELTA
    ) -> np.ndarray:
        """Uniform sample of N_δ(x) ∩ space: the box of half-width δ·range, clipped to the range."""
        if not 0.0 < delta <= 1.0:
            raise ScenarioError(f"delta must be in (0, 1], got {delta}")
        u = self.normalise(self.validate(x))
        lo, hi = np.clip(u - delta, 0.0, 1.0), np.clip(u + delta, 0.0, 1.0)
        return self.denormalise(rng.uniform(lo, hi))

    def scenario_id(self, x: np.ndarray, seed: int, variant: str = "") -> str:
        """A stable id for (logical scenario, vector, seed[, variant]): the same inputs give the
        same id. `variant` (e.g. a non-default ADS profile) is hashed in when not empty, so the
        ids of runs without one are as they always were."""
        arr = self.validate(x)
        h = hashlib.sha1(f"{self.name}|{int(seed)}|".encode())
        if variant:
            h.update(f"{variant}|".encode())
        h.update(arr.astype("<f8").tobytes())  # exact: two vectors differing in 1 ulp differ
        digest = h.hexdigest()
        return f"{self.name}-{digest[:12]}"
