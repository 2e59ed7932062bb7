"""S2 of the paper (§V "Logical Scenarios"): a four-way intersection without signals."""

from __future__ import annotations

from evoeye.scenarios.registry import AuditBands, ScenarioSpec
from evoeye.scenarios.space import LogicalScenario, Parameter

P = Parameter
SHIPPED = "evoeye.monitor.pretrained"  # its version folders, each card naming its scenario

SPACE = LogicalScenario(
    name="unprotected-intersection",
    description=(
        "Four-way intersection without signals; the ego drives straight from south to north, "
        "starting a seeded 20–160 m before the box. Five NPCs: an opposing left turn "
        "(north→east), lateral crossings from the west and from the east, a right-turn merge "
        "into the ego's exit lane (east→north) and a left-turn merge (west→north), each timed "
        "relative to the ego's arrival. The turners yield to the ego; the crossings do not, "
        "and the west crossing ignores that its road gives way."
    ),
    parameters=(
        P("opp_left_speed_mps", 7.0, 13.0, "m/s", "opposing left-turner speed", actor="opp_left"),
        P(
            "opp_left_offset_s",
            -3.0,
            3.0,
            "s",
            "arrives at its conflict with the ego's path this long after the ego would",
            actor="opp_left",
        ),
        P(
            "cross_west_speed_mps",
            7.0,
            13.0,
            "m/s",
            "crossing vehicle from the west, speed",
            actor="cross_west",
        ),
        P(
            "cross_west_offset_s",
            -0.75,
            0.75,
            "s",
            "arrives at its conflict with the ego's path this long after the ego would",
            actor="cross_west",
        ),
        P(
            "cross_east_speed_mps",
            7.0,
            13.0,
            "m/s",
            "crossing vehicle from the east, speed",
            actor="cross_east",
        ),
        P(
            "cross_east_offset_s",
            -0.75,
            0.75,
            "s",
            "arrives at its conflict with the ego's path this long after the ego would",
            actor="cross_east",
        ),
        P(
            "right_merge_speed_mps",
            7.0,
            13.0,
            "m/s",
            "east→north right-turn merger, speed",
            actor="right_merge",
        ),
        P(
            "right_merge_offset_s",
            -3.0,
            3.0,
            "s",
            "arrives at its conflict with the ego's path this long after the ego would",
            actor="right_merge",
        ),
        P(
            "left_merge_speed_mps",
            7.0,
            13.0,
            "m/s",
            "west→north left-turn merger, speed",
            actor="left_merge",
        ),
        P(
            "left_merge_offset_s",
            -3.0,
            3.0,
            "s",
            "arrives at its conflict with the ego's path this long after the ego would",
            actor="left_merge",
        ),
    ),
)

SCENARIO = ScenarioSpec(
    SPACE,
    world="evoeye.sim.intersection:build_intersection",
    label="S2: a four-way intersection without signals",
    bands=AuditBands(collision_rate=(0.50, 0.85)),  # the paper's rate is 77 %
    # the cautious stack collides in 4.5 % of its runs here: the rare-failure regime of the
    # sample-efficiency study (evoeye.results.efficiency.config)
    ads_profiles=("default", "cautious"),
    demo_monitor=SHIPPED,
    demo_runs=60,
    paper_runs=(132, 177 + 45),
)
