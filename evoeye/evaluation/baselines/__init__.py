"""The baselines a monitor is compared with, one module each, registered once.

A module of this package declares `BASELINE = BaselineSpec(...)` (or a tuple, for a variant of
the same rule); a third-party package adds one through the entry point group
`evoeye.baselines` (docs/extending.md). Every list of baselines in evoeye (`evaluation.monitors.
BASELINES`, the rules, the reports' labels, the defaults of `evoeye evaluate` and `evoeye
results`) is read from `BASELINE_SPECS`. A declaration imports its monitor only when built, so
that the command line can list the names without loading numpy or torch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from evoeye.plugins import Registry, RegistryError

if TYPE_CHECKING:
    from evoeye.monitor.protocol import Monitor
    from evoeye.paths import DataRoot
    from evoeye.store import SplitSpec

ENTRY_POINT_GROUP = "evoeye.baselines"


@dataclass(frozen=True)
class BaselineSpec:
    """One baseline: a rule (`rule`: makes the monitor, no data) or a trained one (`family`:
    the monitor family whose RQ1 `fit` trains it on a scenario's train split)."""

    name: str
    label: str  # how reports name it, e.g. "TTC-2D"
    rule: Callable[[], Monitor] | None = None
    family: str | None = None
    order: int = 100  # where tables list it (then by name)

    def __post_init__(self) -> None:
        if (self.rule is None) == (self.family is None):
            raise RegistryError(f"baseline {self.name!r}: give a rule or a family, not both "
                                "or neither")

    @property
    def is_rule(self) -> bool:
        return self.rule is not None

    def build(self, root: DataRoot, scenario: str, splits: SplitSpec) -> Monitor:
        """The monitor, ready to score `scenario`'s windows (a trained one fitted, or found
        again, on its train split under `splits`)."""
        if self.rule is not None:
            return self.rule()
        import evoeye.baselines  # noqa: F401  (registers the baselines' monitor families)
        from evoeye.monitor.families import FAMILIES

        return FAMILIES[self.family].fit(root, scenario, splits)


BASELINE_SPECS: Registry[BaselineSpec] = Registry(
    "baseline", package=__name__, attr="BASELINE", group=ENTRY_POINT_GROUP, cls=BaselineSpec,
    order=lambda spec: spec.order)


def rule_names() -> tuple[str, ...]:
    """The rule-based baselines (no data, no training)."""
    return tuple(name for name, spec in BASELINE_SPECS.items() if spec.is_rule)
