"""Logical scenario spaces, looked up by name."""

from evoeye.scenarios.catalog import HIGHWAY_CUT_IN, INTERSECTION
from evoeye.scenarios.space import DEFAULT_DELTA, LogicalScenario, Parameter, ScenarioError

SCENARIOS: dict[str, LogicalScenario] = {s.name: s for s in (HIGHWAY_CUT_IN, INTERSECTION)}
# Runs that were recorded, not simulated here (`evoeye import`): a space with no parameter, so a
# recording's run metadata fits it. Never simulated, sampled or searched (not in SCENARIOS).
EXTERNAL = LogicalScenario("external", "a run recorded by another stack and imported", ())
RECORDED: dict[str, LogicalScenario] = {EXTERNAL.name: EXTERNAL}


def get_scenario(name: str) -> LogicalScenario:
    """The logical scenario called `name` (simulated or recorded), or a ScenarioError listing
    the known ones."""
    known = SCENARIOS.get(name) or RECORDED.get(name)
    if known is None:
        names = sorted(SCENARIOS) + sorted(RECORDED)
        raise ScenarioError(f"unknown logical scenario {name!r}; known: {names}")
    return known


__all__ = [
    "DEFAULT_DELTA",
    "EXTERNAL",
    "RECORDED",
    "SCENARIOS",
    "LogicalScenario",
    "Parameter",
    "ScenarioError",
    "get_scenario",
]
