"""Named ADS profiles: which stack drives the ego. A regime is a logical scenario and a profile.

A run records its profile (`RunSpec.ads`, the run metadata's `ads_profile`, the `scenarios`
column), so it is simulated, explained and re-simulated with the stack that made it.

* `default` — the tuned stack of `ADSConfig()`: collisions are common (≈ 25 % of uniform
  highway cut-in runs, ≈ 55 % at the intersection).
* `cautious` — `ADSConfig.cautious()`: 100 ms latency, conservative gap acceptance, every
  plausible mode planned against, an earlier AEB also for predicted crossings.
* `firm-yield` — the default stack, except that it yields to crossing traffic with up to its
  comfort braking (3.5 m/s²) instead of calling itself committed beyond 1.75 m/s²: the
  decision a production stack makes. At the intersection its collisions are rare and come
  from every module.
* `defensive` — the cautious stack keeping a 2 s time headway (cautious: 1.5 s) and braking in
  earnest at a TTC of 1.5 s (cautious: 1.2 s). On the highway cut-in its collisions are rarer
  still: 1 of 2 000 uniform runs on the seed it was chosen on (≈ 0.05 %), the rare-failure
  protocol's ≈ 0.1 % regime (docs/rare.md).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from evoeye.ads.config import ADSConfig, PlanningConfig

DEFAULT_PROFILE = "default"


def _firm_yield() -> ADSConfig:
    planning = PlanningConfig()
    return ADSConfig(planning=replace(planning,
                                      yield_decel_max_mps2=planning.comfort_decel_mps2))


def _defensive() -> ADSConfig:
    cautious = ADSConfig.cautious()
    return replace(cautious, planning=replace(cautious.planning, time_headway_s=2.0,
                                              emergency_ttc_s=1.5))


ADS_PROFILES: dict[str, Callable[[], ADSConfig]] = {
    DEFAULT_PROFILE: ADSConfig,
    "cautious": ADSConfig.cautious,
    "firm-yield": _firm_yield,
    "defensive": _defensive,
}


class UnknownProfileError(ValueError):
    """An ADS profile name that is not in ADS_PROFILES."""


def check_profile(name: str) -> str:
    """`name` if it names a profile, else UnknownProfileError listing the known ones."""
    if name not in ADS_PROFILES:
        raise UnknownProfileError(f"unknown ADS profile {name!r}; known: "
                                  f"{', '.join(ADS_PROFILES)}")
    return name


def ads_profile(name: str = DEFAULT_PROFILE) -> ADSConfig:
    """The ADSConfig of a named profile."""
    return ADS_PROFILES[check_profile(name)]()
