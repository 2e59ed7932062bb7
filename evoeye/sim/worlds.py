"""World variants: a logical scenario's world with something added, chosen per run like the
ADS profile (`RunSpec.world`, `evoeye simulate --world`).

A variant changes the world, not the parameter space: the same vector and seed give the same
NPCs plus the variant's. A run records its variant (the run metadata's `world`, written only
when it is not `default`), so it is re-simulated — supervised, audited — in the world that made
it, and it gets ids of its own; the default world's runs, ids and logs are as they always were.

* `follower` (highway-cut-in): a car behind the ego in its lane (`highway.add_follower`), an
  IDM driver at 1 s headway who acts 1 s late, so that a needless hard brake can get the ego
  struck from behind: the price of a false intervention (`evoeye supervise`).
"""

from __future__ import annotations

from collections.abc import Callable

from evoeye.ads.profiles import DEFAULT_PROFILE
from evoeye.sim.highway import add_follower
from evoeye.sim.world import World

DEFAULT_WORLD = "default"

# (the built world, its parameters, the ego's cruise speed) → the world of the variant
WorldVariant = Callable[[World, dict[str, float], float], World]
WORLD_VARIANTS: dict[str, dict[str, WorldVariant]] = {  # variant → logical scenario → how
    "follower": {"highway-cut-in": add_follower},
}
WORLD_NAMES = (DEFAULT_WORLD, *WORLD_VARIANTS)


class UnknownWorldError(ValueError):
    """A world variant that does not exist, or not for this logical scenario."""


def check_world(name: str, scenario: str | None = None) -> str:
    """`name` if it names a world (for `scenario`, if given), else UnknownWorldError."""
    if name == DEFAULT_WORLD:
        return name
    if name not in WORLD_VARIANTS:
        raise UnknownWorldError(f"unknown world {name!r}; known: {', '.join(WORLD_NAMES)}")
    if scenario is not None and scenario not in WORLD_VARIANTS[name]:
        raise UnknownWorldError(f"world {name!r} has no variant of {scenario}; it has: "
                                f"{', '.join(WORLD_VARIANTS[name])}")
    return name


def vary(name: str, scenario: str, world: World, params: dict[str, float],
         cruise_mps: float) -> World:
    """The world of variant `name` (the default world as it is)."""
    if check_world(name, scenario) == DEFAULT_WORLD:
        return world
    return WORLD_VARIANTS[name][scenario](world, params, cruise_mps)


def run_variant(ads: str = DEFAULT_PROFILE, world: str = DEFAULT_WORLD) -> str:
    """What a run's id hashes in beside its scenario, vector and seed: '' for the default
    profile and world (ids as before profiles existed), else the profile and `world=<name>`."""
    parts = [ads] if ads != DEFAULT_PROFILE else []
    if world != DEFAULT_WORLD:
        parts.append(f"world={world}")
    return "|".join(parts)
