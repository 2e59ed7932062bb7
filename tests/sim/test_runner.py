"""One run: (scenario vector, seed) → Episode; reproducible, bounded, failures captured."""

from dataclasses import replace

import numpy as np
import pytest

from evoeye.scenarios import SCENARIO_SPECS, SCENARIOS, get_scenario
from evoeye.sim import runner
from evoeye.sim.runner import SimConfig, run_episode, run_spec

HIGHWAY = get_scenario("highway-cut-in")


def spec_for(scenario, seed=0, draw=0):
    x = get_scenario(scenario).sample(np.random.default_rng(draw))
    return run_spec(scenario, x, seed)


def frames_equal(a, b):
    for fa, fb in zip(a.frames, b.frames, strict=True):
        np.testing.assert_array_equal(fa.scene.x_m, fb.scene.x_m)
        for ma, mb in zip(
            (fa.messages.obstacles, fa.messages.predictions, fa.messages.plan, fa.messages.control),
            (fb.messages.obstacles, fb.messages.predictions, fb.messages.plan, fb.messages.control),
            strict=True,
        ):
            for k, v in ma.to_dict().items():
                np.testing.assert_array_equal(np.asarray(v), np.asarray(mb.to_dict()[k]))


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_same_spec_gives_the_same_run(scenario):
    spec = spec_for(scenario, seed=11, draw=3)
    a, b = run_episode(spec), run_episode(spec)
    assert a.outcome == b.outcome
    frames_equal(a, b)


def test_a_different_seed_changes_the_ads_noise_but_not_the_scenario():
    x = HIGHWAY.sample(np.random.default_rng(0))
    a = run_episode(run_spec("highway-cut-in", x, 1), SimConfig(duration_s=2.0))
    b = run_episode(run_spec("highway-cut-in", x, 2), SimConfig(duration_s=2.0))
    np.testing.assert_array_equal(a.frames[0].scene.x_m, b.frames[0].scene.x_m)
    assert a.frames[0].messages.localization.x_m != b.frames[0].messages.localization.x_m


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_runs_last_20_s_or_end_2_s_after_the_first_collision(scenario):
    for draw in range(6):
        ep = run_episode(spec_for(scenario, draw=draw))
        o = ep.outcome
        assert o.status == "ok", o.reason
        times = [f.scene.t_s for f in ep.frames]
        assert np.allclose(np.diff(times), 0.05)
        hits = [f.scene.t_s for f in ep.frames if f.scene.ego_collision]
        assert o.collided == bool(hits)
        if o.collided:
            assert o.collision_time_s == hits[0]
            assert o.other_actor is not None and o.other_actor > 0
            assert times[-1] == pytest.approx(o.collision_time_s + 2.0)
        else:
            assert len(ep.frames) == 400 and o.duration_s == pytest.approx(20.0)


def test_a_run_that_raises_is_a_failed_episode_not_a_crash(monkeypatch):
    def broken(params, rng):
        raise RuntimeError("road network unavailable")

    monkeypatch.setitem(SCENARIO_SPECS, "highway-cut-in",
                        replace(SCENARIO_SPECS["highway-cut-in"], world=broken))
    ep = run_episode(spec_for("highway-cut-in"))
    assert ep.outcome.status == "failed"
    assert "road network unavailable" in ep.outcome.reason
    assert ep.frames == []


def test_a_nan_in_the_world_is_a_failed_episode(monkeypatch):
    real = runner.world_builder("highway-cut-in")

    def poisoned(params, rng):
        world, cruise = real(params, rng)
        world.npcs[0].speed = float("nan")
        return world, cruise

    monkeypatch.setitem(SCENARIO_SPECS, "highway-cut-in",
                        replace(SCENARIO_SPECS["highway-cut-in"], world=poisoned))
    ep = run_episode(spec_for("highway-cut-in"))
    assert ep.outcome.status == "failed"
    assert "non-finite" in ep.outcome.reason


def test_run_spec_rejects_an_out_of_range_vector():
    x = HIGHWAY.sample(np.random.default_rng(0))
    x[0] = -5.0
    with pytest.raises(ValueError, match="ego_speed_mps"):
        run_spec("highway-cut-in", x, 0)


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_every_logical_scenario_has_a_world_whose_actors_all_exist_from_the_start(scenario):
    space = get_scenario(scenario)
    for draw in range(3):
        params = space.as_dict(space.sample(np.random.default_rng(draw)))
        world, cruise = runner.world_builder(scenario)(params, np.random.default_rng(draw))
        first = world.scene()
        assert cruise > 0.0 and first.n >= 2
        for _ in range(20):  # 1 s with the ego holding its speed
            world.step(0.0, 0.0, 0.05)
        later = world.scene()
        np.testing.assert_array_equal(later.actor_id, first.actor_id)  # nobody pops in
        assert runner.scene_finite(later)
