"""S1 of the paper (§V "Logical Scenarios"): a highway with a braking lead and cut-ins."""

from __future__ import annotations

from evoeye.scenarios.registry import AuditBands, ScenarioSpec
from evoeye.scenarios.space import LogicalScenario, Parameter

P = Parameter
SHIPPED = "evoeye.monitor.pretrained"  # its version folders, each card naming its scenario

SPACE = LogicalScenario(
    name="highway-cut-in",
    description=(
        "Three-lane highway; the ego starts in the middle lane with six NPCs: a lead vehicle that "
        "may brake suddenly, a cut-in from each adjacent lane, a follower in each adjacent lane "
        "and an overtaker coming from behind in the left lane."
    ),
    parameters=(
        P("ego_speed_mps", 20.0, 30.0, "m/s", "ego initial and set cruise speed", actor="ego"),
        P(
            "lead_gap_m",
            20.0,
            70.0,
            "m",
            "initial bumper gap to the lead vehicle in the ego lane",
            actor="lead",
        ),
        P(
            "lead_speed_mps",
            15.0,
            30.0,
            "m/s",
            "lead vehicle desired speed (it starts at the ego's speed)",
            actor="lead",
        ),
        P(
            "lead_brake_time_s",
            3.0,
            16.0,
            "s",
            "when the lead vehicle starts braking",
            actor="lead",
        ),
        P(
            "lead_brake_decel_mps2",
            2.5,
            6.0,
            "m/s²",
            "how hard the lead vehicle brakes",
            actor="lead",
        ),
        P(
            "lead_brake_duration_s",
            2.0,
            6.0,
            "s",
            "how long the lead vehicle keeps braking",
            actor="lead",
        ),
        P(
            "left_cutin_gap_m",
            10.0,
            100.0,
            "m",
            "left cut-in NPC start, ahead (+) of the ego",
            actor="left_cutin",
        ),
        P("left_cutin_speed_mps", 8.0,
            24.0, "m/s", "left cut-in NPC speed", actor="left_cutin"),
        P(
            "left_cutin_trigger_gap_m",
            5.0,
            60.0,
            "m",
            "the left NPC cuts in when its bumper gap ahead of the ego crosses this value",
            actor="left_cutin",
        ),
        P(
            "left_cutin_duration_s",
            2.6,
            5.0,
            "s",
            "left lane-change duration (lower = sharper)",
            actor="left_cutin",
        ),
        P(
            "right_cutin_gap_m",
            10.0,
            100.0,
            "m",
            "right cut-in NPC start, ahead (+) of the ego",
            actor="right_cutin",
        ),
        P(
            "right_cutin_speed_mps",
            8.0,
            24.0,
            "m/s",
            "right cut-in NPC speed",
            actor="right_cutin",
        ),
        P(
            "right_cutin_trigger_gap_m",
            5.0,
            60.0,
            "m",
            "the right NPC cuts in when its bumper gap ahead of the ego crosses this value",
            actor="right_cutin",
        ),
        P(
            "right_cutin_duration_s",
            2.6,
            5.0,
            "s",
            "right lane-change duration",
            actor="right_cutin",
        ),
        P(
            "left_follow_gap_m",
            -60.0,
            80.0,
            "m",
            "left-lane traffic start relative to the ego",
            actor="left_follow",
        ),
        P(
            "left_follow_speed_mps",
            18.0,
            33.0,
            "m/s",
            "left-lane traffic speed",
            actor="left_follow",
        ),
        P(
            "right_follow_gap_m",
            -60.0,
            80.0,
            "m",
            "right-lane traffic start relative to the ego",
            actor="right_follow",
        ),
        P(
            "right_follow_speed_mps",
            15.0,
            30.0,
            "m/s",
            "right-lane traffic speed",
            actor="right_follow",
        ),
        P(
            "overtaker_gap_m",
            -80.0,
            -15.0,
            "m",
            "overtaker start behind the ego (left lane)",
            actor="overtaker",
        ),
        P(
            "overtaker_speed_mps",
            25.0,
            38.0,
            "m/s",
            "overtaker speed; it cuts back in once ahead",
            actor="overtaker",
        ),
    ),
)

SCENARIO = ScenarioSpec(
    SPACE,
    world="evoeye.sim.highway:build_highway",
    label="S1: a highway, a braking lead and cut-ins",
    # the paper's rate is 34 %; the band is wide enough for the ADS's failure mix to move
    bands=AuditBands(collision_rate=(0.20, 0.50)),
    demo_monitor=SHIPPED,
    demo_runs=120,  # >= 10 test collisions at its rate
    paper_runs=(75, 107 + 25),
)
