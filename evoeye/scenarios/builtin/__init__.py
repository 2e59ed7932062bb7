"""The built-in logical scenarios: each module declares one `SCENARIO` (a ScenarioSpec), found
by `evoeye.scenarios.SCENARIO_SPECS`; a new module here is a new scenario, nothing else to edit."""
