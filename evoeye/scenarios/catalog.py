"""The two logical scenarios of the paper (§V "Logical Scenarios"), declared as data."""

from __future__ import annotations

from evoeye.scenarios.space import LogicalScenario, Parameter

P = Parameter

HIGHWAY_CUT_IN = LogicalScenario(
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

INTERSECTION = LogicalScenario(
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
