"""Named ADS profiles: what each changes, ids of their own, and the run driven by its profile."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.ads import ADSConfig, ads_profile
from evoeye.ads.profiles import ADS_PROFILES, UnknownProfileError
from evoeye.batch import plan_uniform
from evoeye.scenarios import get_scenario
from evoeye.sim.runner import SimConfig, run_episode, run_spec

SHORT = SimConfig(duration_s=1.5)


def test_every_profile_builds_and_firm_yield_yields_up_to_comfort_braking() -> None:
    for name in ADS_PROFILES:
        assert isinstance(ads_profile(name), ADSConfig)
    firm = ads_profile("firm-yield").planning
    assert firm.yield_decel_max_mps2 == firm.comfort_decel_mps2 == 3.5
    assert ADSConfig().planning.yield_decel_max_mps2 < 3.5  # the default calls itself committed
    assert ads_profile("cautious") == ADSConfig.cautious()


def test_an_unknown_profile_names_the_known_ones() -> None:
    x = get_scenario("highway-cut-in").sample(np.random.default_rng(0))
    with pytest.raises(UnknownProfileError, match="known: default, cautious, firm-yield"):
        run_spec("highway-cut-in", x, 1, ads="reckless")


def test_a_profile_gets_ids_of_its_own_and_default_ids_do_not_change() -> None:
    space = get_scenario("unprotected-intersection")
    x = space.sample(np.random.default_rng(4))
    default = run_spec(space.name, x, 7)
    assert default.scenario_id == space.scenario_id(x, 7)  # as before profiles existed
    ids = {run_spec(space.name, x, 7, ads=name).scenario_id for name in ADS_PROFILES}
    assert len(ids) == len(ADS_PROFILES)


def test_a_batch_of_a_profile_draws_the_same_scenarios_under_a_name_of_its_own() -> None:
    default = plan_uniform("highway-cut-in", 3, 5)
    firm = plan_uniform("highway-cut-in", 3, 5, ads="firm-yield")
    assert [s.params for s in firm] == [s.params for s in default]
    assert [s.seed for s in firm] == [s.seed for s in default]
    assert {s.batch for s in firm} == {"uniform-firm-yield-seed5"}
    assert {s.ads for s in firm} == {"firm-yield"} and {s.ads for s in default} == {"default"}


def test_the_run_is_driven_by_its_profile() -> None:
    x = get_scenario("highway-cut-in").sample(np.random.default_rng(2))
    spec = run_spec("highway-cut-in", x, 3, ads="cautious")
    by_name = run_episode(spec, SHORT)
    by_config = run_episode(run_spec("highway-cut-in", x, 3), SHORT,
                            ads_config=ADSConfig.cautious())
    default = run_episode(run_spec("highway-cut-in", x, 3), SHORT)

    def track_x(ep):
        return [tuple(f.messages.obstacles.x_m) for f in ep.frames]

    assert track_x(by_name) == track_x(by_config)  # the cautious stack's 100 ms latency …
    assert track_x(by_name) != track_x(default)  # … is not the default's 250 ms
