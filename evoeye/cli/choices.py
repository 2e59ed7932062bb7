"""Options whose values are the registered logical scenarios: their help lists the names and
their callback refuses any other, naming the known ones, before anything runs.

The names are read from the registry (`evoeye.scenarios.SCENARIO_SPECS`, built-in and
third-party), which imports no numpy; nothing here keeps a copy of them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import typer

V = TypeVar("V", str, list[str], None)


def scenario_names(*, recorded: bool = False) -> tuple[str, ...]:
    """The simulated scenarios' names (and, with `recorded`, the recorded ones: `external`)."""
    from evoeye.scenarios import RECORDED, SCENARIOS

    return (*SCENARIOS, *(RECORDED if recorded else ()))


def scenario_help(text: str, *, recorded: bool = False) -> str:
    """`text` followed by the names the option takes."""
    return f"{text} One of: {', '.join(scenario_names(recorded=recorded))}."


def scenario_check(*, recorded: bool = False) -> Callable[[V], V]:
    """Typer callback refusing a --scenario value that is not a registered scenario (nor, with
    `recorded`, a recorded one); with its one-line reason and the names it takes."""
    def check(value: V) -> V:
        from evoeye.scenarios import ScenarioError, get_scenario, simulable

        for name in [value] if isinstance(value, str) else value or []:
            try:
                get_scenario(name) if recorded else simulable(name)
            except ScenarioError as exc:
                raise typer.BadParameter(str(exc)) from None
        return value
    return check
