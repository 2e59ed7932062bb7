"""S3: an urban street where pedestrians cross, one of them hidden by parked cars.

Designed so that its collisions come from every module of the stack (docs/world.md); the world
is `evoeye/sim/crossing.py`.
"""

from __future__ import annotations

from evoeye.scenarios.registry import AuditBands, ScenarioSpec
from evoeye.scenarios.space import LogicalScenario, Parameter

P = Parameter
SHIPPED = "evoeye.monitor.pretrained"  # its version folders, each card naming its scenario


def _walker(name: str, what: str) -> tuple[Parameter, ...]:
    """Where a pedestrian crosses, how fast it walks and when it reaches the ego's path."""
    return (
        P(f"{name}_ahead_m", 30.0, 180.0, "m",
          f"{what}: where it crosses the ego's lane, ahead of the ego's start", actor=name),
        P(f"{name}_speed_mps", 1.0, 2.2, "m/s", f"{what}: walking speed", actor=name),
        P(f"{name}_offset_s", -2.5, 0.0, "s",
          f"{what}: reaches the ego's lane centre this long after the ego would at its set "
          "speed, walking without a stop", actor=name),
    )


SPACE = LogicalScenario(
    name="occluded-crossing",
    description=(
        "A straight urban street with cars parked along one kerb; the ego drives its lane at "
        "8–14 m/s. Three pedestrians cross it, each timed relative to the ego's arrival: one "
        "steps out between the parked cars (hidden until it does), one waits at the open kerb "
        "and goes once the ego is close, and one walks along the open "
        "pavement and turns across."
    ),
    parameters=(
        P("ego_speed_mps", 7.0, 12.5, "m/s", "ego initial and set cruise speed", actor="ego"),
        P("parked_gap_m", 0.8, 4.0, "m",
          "bumper gap between the cars parked along the kerb (smaller: a denser wall)",
          actor="parked"),
        *_walker("hidden_ped", "the pedestrian who steps out between the parked cars"),
        *_walker("kerb_ped", "the pedestrian who waits at the open kerb"),
        P("kerb_ped_go_s", 3.0, 5.5, "s",
          "the waiting pedestrian steps off once the ego is this long from its crossing",
          actor="kerb_ped"),
        *_walker("turn_ped", "the pedestrian who walks along the open pavement and turns across"),
    ),
)

SCENARIO = ScenarioSpec(
    SPACE,
    world="evoeye.sim.crossing:build_crossing",
    label="S3: a street, pedestrians crossing between parked cars",
    # 24 % on the tuning seed; the band is that ± about 2.5 binomial SDs of 200 runs, rounded
    # (docs/results/realism.md)
    bands=AuditBands(collision_rate=(0.15, 0.40)),
    demo_monitor=SHIPPED,
    demo_runs=120,
)
