"""Which monitors to evaluate: the baselines by name, trained monitors by version.

The baselines are the registered ones (`evoeye.evaluation.baselines`, one module each, and
third-party ones through an entry point): TTC, TTC-2D and RSS (also `rss-2s`: CARLA's 2 s
response time for the other vehicles) are rules and need no data; the trained ones (AEM, the
context-only control) are monitor families with an RQ1 `fit` on the scenario's train split
(`evoeye.baselines.families`, trained once and found again). A version of any family loads
through the family registry (`evoeye.monitor.families`), whatever its family.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

import evoeye.baselines  # noqa: F401  (registers the trained baselines' monitor families)
from evoeye.evaluation.baselines import BASELINE_SPECS
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES, load_version
from evoeye.monitor.protocol import Monitor
from evoeye.paths import DataRoot
from evoeye.plugins import View
from evoeye.store import SplitSpec

BaselineBuilder = Callable[[DataRoot, str, SplitSpec], Monitor]


# baseline name → `(root, scenario, splits) -> Monitor`, read from the registry
BASELINES: View[BaselineBuilder] = View(BASELINE_SPECS, lambda spec: spec.build)


def baseline_monitors(root: DataRoot, scenario: str,
                      splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
                      names: Iterable[str] = tuple(BASELINES)) -> list[Monitor]:
    """The named baselines, ready to score windows of `scenario`."""
    names = list(names)
    unknown = [n for n in names if n not in BASELINES]
    if unknown:
        raise KeyError(f"unknown baseline(s) {unknown}; known: {sorted(BASELINES)}")
    return [BASELINES[n](root, scenario, splits) for n in names]


def load_monitors(root: DataRoot, versions: Iterable[str]) -> list[Monitor]:
    """Trained monitors by version, each through its family (by the version's prefix)."""
    return [load_version(root, v) for v in versions]


def train_fusion(root: DataRoot, scenario: str, *, context_len: int = 5,
                 modules: tuple[str, ...] | None = None, seed: int = 0,
                 splits: SplitSpec | None = None, **overrides) -> Monitor:
    """Train (or let the registry reuse) a FusionMonitor for `scenario` and load it;
    `overrides` go to train_monitor (epochs=…, lr=…)."""
    fusion = FAMILIES[DEFAULT_FAMILY]
    kwargs: dict = {"context_len": context_len, "seed": seed, **overrides}
    if modules is not None:
        kwargs["modules"] = modules
    if splits is not None:
        kwargs["splits"] = splits
    return fusion.load(root, fusion.train(root, scenario, **kwargs))


def monitor_context_len(monitor: Monitor, default: int = 5) -> int:
    """The context length L a monitor reads (its `context_len`, else `default`)."""
    return int(getattr(monitor, "context_len", default) or default)


def check_scores(monitor: Monitor, scores: np.ndarray, n: int, *,
                 unit_interval: bool = True) -> np.ndarray:
    """The monitor's scores as (n,) float64, finite and (with `unit_interval`: risks, not
    logits) in [0, 1], or a clear error."""
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    if s.shape != (n,):
        raise ValueError(f"{monitor.name} returned {s.shape} scores for {n} windows")
    if not np.isfinite(s).all():
        raise ValueError(f"{monitor.name} returned non-finite scores")
    if unit_interval and (s.min(initial=0.0) < 0.0 or s.max(initial=0.0) > 1.0):
        raise ValueError(f"{monitor.name} returned scores outside [0, 1]")
    return s
