"""Logical scenario spaces, looked up by name in the registry (`registry.SCENARIO_SPECS`)."""

from evoeye.plugins import View
from evoeye.scenarios.registry import SCENARIO_SPECS, AuditBands, ScenarioSpec
from evoeye.scenarios.space import DEFAULT_DELTA, LogicalScenario, Parameter, ScenarioError

# the simulated scenarios' spaces: built-in and third-party, read from the registry
SCENARIOS: View[LogicalScenario] = View(SCENARIO_SPECS, lambda spec: spec.space)
# Runs that were recorded, not simulated here (`evoeye import`): a space with no parameter, so a
# recording's run metadata fits it. Never simulated, sampled or searched (not in SCENARIOS).
EXTERNAL = LogicalScenario("external", "a run recorded by another stack and imported", ())
RECORDED: dict[str, LogicalScenario] = {EXTERNAL.name: EXTERNAL}


def get_scenario(name: str) -> LogicalScenario:
    """The logical scenario called `name` (simulated or recorded), or a ScenarioError listing
    the known ones."""
    known = SCENARIOS.get(name) or RECORDED.get(name)
    if known is None:
        raise ScenarioError(f"unknown logical scenario {name!r}; known: "
                            f"{', '.join([*SCENARIOS, *RECORDED])}")
    return known


def simulable(name: str) -> ScenarioSpec:
    """The registered scenario `name`, or a ScenarioError naming the ones that can be
    simulated (a recorded one, such as `external`, cannot)."""
    spec = SCENARIO_SPECS.get(name)
    if spec is None:
        what = (f"logical scenario {name!r} is recorded, not simulated" if name in RECORDED
                else f"unknown logical scenario {name!r}")
        raise ScenarioError(f"{what}; simulated ones: {', '.join(SCENARIOS)}")
    return spec


__all__ = [
    "DEFAULT_DELTA",
    "EXTERNAL",
    "RECORDED",
    "SCENARIOS",
    "SCENARIO_SPECS",
    "AuditBands",
    "LogicalScenario",
    "Parameter",
    "ScenarioError",
    "ScenarioSpec",
    "get_scenario",
    "simulable",
]
