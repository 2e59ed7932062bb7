"""Logical scenario spaces, looked up by name."""

from evoeye.scenarios.catalog import HIGHWAY_CUT_IN, INTERSECTION
from evoeye.scenarios.space import DEFAULT_DELTA, LogicalScenario, Parameter, ScenarioError

SCENARIOS: dict[str, LogicalScenario] = {s.name: s for s in (HIGHWAY_CUT_IN, INTERSECTION)}


def get_scenario(name: str) -> LogicalScenario:
    """The logical scenario called `name`, or a ScenarioError listing the known ones."""
    try:
        return SCENARIOS[name]
    except KeyError:
        known = sorted(SCENARIOS)
        raise ScenarioError(f"unknown logical scenario {name!r}; known: {known}") from None


__all__ = [
    "DEFAULT_DELTA",
    "SCENARIOS",
    "LogicalScenario",
    "Parameter",
    "ScenarioError",
    "get_scenario",
]
