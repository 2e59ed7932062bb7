"""A logical scenario is one module, registered once: `SCENARIO = ScenarioSpec(...)`.

The spec holds everything a scenario brings: its parameter space, its world builder, its
display name, its audit bands, the ADS profiles it is studied with, and its shipped demo
monitor, if any. The built-in ones are the modules of `evoeye.scenarios.builtin`; a third-party
package adds one through the entry point group `evoeye.scenarios` (docs/extending.md). Every
list of scenarios in evoeye is read from `SCENARIO_SPECS`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from importlib import import_module
from typing import Any

from evoeye.plugins import Registry
from evoeye.scenarios.space import LogicalScenario, ScenarioError

ENTRY_POINT_GROUP = "evoeye.scenarios"


@dataclass(frozen=True)
class AuditBands:
    """What `evoeye audit` demands of a scenario's batches (docs/audit.md)."""

    collision_rate: tuple[float, float]  # the share of runs that collide, inclusive
    clock_auroc_max: float = 0.70  # the clock-only control may not predict failures better
    # a monitor must beat the context-only control by 5 AUROC points (RQ1), so the control must
    # leave that much room
    context_auroc_max: float = 0.95

    def __post_init__(self) -> None:
        lo, hi = self.collision_rate
        if not 0.0 <= lo <= hi <= 1.0:
            raise ScenarioError(f"collision-rate band {self.collision_rate}: need 0 <= lo <= hi "
                                "<= 1")


@dataclass(frozen=True)
class ScenarioSpec:
    """One logical scenario and everything it brings.

    `world` is the world builder `(params, rng) -> (World, cruise_mps)`, or its import path
    "package.module:function" (read when a run is built, so the registry stays light).
    """

    space: LogicalScenario
    world: str | Callable[..., Any]
    label: str  # what it is, in a few words, beside its name in summaries
    bands: AuditBands
    ads_profiles: tuple[str, ...] = ("default",)  # the stacks it is studied with, default first
    # the package whose version folders hold its shipped demo monitor (the one whose card names
    # this scenario), if it ships one: `evoeye demo` skips a scenario without
    demo_monitor: str | None = None
    demo_runs: int = 60  # `evoeye demo`'s runs: enough for >= 10 test collisions
    paper_runs: tuple[int, int] | None = None  # the paper's test runs and initial runs

    @property
    def name(self) -> str:
        return self.space.name

    def world_builder(self) -> Callable[..., Any]:
        """The world builder, imported from its path if given as one."""
        if callable(self.world):
            return self.world
        module, _, attr = self.world.partition(":")
        return getattr(import_module(module), attr)


SCENARIO_SPECS: Registry[ScenarioSpec] = Registry(
    "logical scenario", package="evoeye.scenarios.builtin", attr="SCENARIO",
    group=ENTRY_POINT_GROUP, cls=ScenarioSpec)
