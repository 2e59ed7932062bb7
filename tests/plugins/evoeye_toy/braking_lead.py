"""A logical scenario in one file: the highway's braking lead alone in the space, every other
actor at the middle of its range. Registered by the entry point
`[project.entry-points."evoeye.scenarios"] braking-lead = "evoeye_toy.braking_lead:SCENARIO"`."""

from evoeye.scenarios import AuditBands, LogicalScenario, Parameter, ScenarioSpec

SPACE = LogicalScenario(
    name="toy-braking-lead",
    description="The highway of S1; only the lead vehicle's gap and braking vary.",
    parameters=(
        Parameter("lead_gap_m", 20.0, 40.0, "m", "initial bumper gap to the lead", actor="lead"),
        Parameter("lead_brake_decel_mps2", 3.0, 6.0, "m/s²", "how hard the lead brakes",
                  actor="lead"),
    ),
)


def build(params: dict[str, float], rng):
    """The highway world with this scenario's parameters, the rest at their range's middle."""
    from evoeye.scenarios import SCENARIOS
    from evoeye.sim.highway import build_highway

    middle = {p.name: (p.low + p.high) / 2 for p in SCENARIOS["highway-cut-in"].parameters}
    return build_highway({**middle, **params}, rng)


SCENARIO = ScenarioSpec(SPACE, world=build, label="toy braking lead",
                        bands=AuditBands(collision_rate=(0.0, 1.0)), demo_runs=8)
