"""World variants: the default world as it always was; the follower behind the ego, whose presence
turns a needless hard brake into a collision from behind."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from evoeye.batch import plan_uniform
from evoeye.sim.highway import FOLLOWER_HEADWAY_S, FOLLOWER_REACTION_S
from evoeye.sim.npc import DriverModel, Npc
from evoeye.sim.runner import build_world, run_episode, run_spec
from evoeye.sim.supervisor import FALLBACKS, Trigger, run_supervised
from evoeye.sim.worlds import UnknownWorldError, run_variant

DT = 0.05
BRAKE_AT_S = 4.0  # the needless brake: a trigger that alarms from here on, for no reason


def _false_alarm(m) -> float:
    return 1.0 if m.localization.t_s >= BRAKE_AT_S - 1e-9 else 0.0


@pytest.fixture(scope="module")
def specs():
    """Two runs of highway-cut-in's uniform batch at seed 0: one collides, one is safe."""
    return plan_uniform("highway-cut-in", 2, 0)


def test_the_default_world_is_as_it_was(specs) -> None:
    crash, safe = specs
    # ids and outcomes recorded before world variants existed (the logs' SHA-256 were equal too)
    assert [s.scenario_id for s in specs] == ["highway-cut-in-6c4bea900f4a",
                                              "highway-cut-in-5963f8f1e3eb"]
    assert {s.world for s in specs} == {"default"} and run_variant() == ""
    o = run_episode(crash).outcome
    assert (o.collided, o.other_actor, o.duration_s) == (True, 1, 8.85)
    assert o.collision_time_s == pytest.approx(6.8, abs=1e-9)
    o = run_episode(safe).outcome
    assert (o.collided, o.duration_s) == (False, 20.0)
    assert o.min_distance_m == pytest.approx(1.9719417586532582, rel=1e-12)


def test_a_variant_gets_ids_and_a_batch_name_of_its_own_for_the_same_scenarios(specs) -> None:
    follow = plan_uniform("highway-cut-in", 2, 0, world="follower")
    assert [s.params for s in follow] == [s.params for s in specs]
    assert [s.seed for s in follow] == [s.seed for s in specs]
    assert {s.world for s in follow} == {"follower"}
    assert {s.batch for s in follow} == {"uniform-follower-seed0"}
    assert not {s.scenario_id for s in follow} & {s.scenario_id for s in specs}
    both = run_spec("highway-cut-in", specs[0].params, specs[0].seed, ads="cautious",
                    world="follower")
    assert both.scenario_id not in {follow[0].scenario_id, run_spec(
        "highway-cut-in", specs[0].params, specs[0].seed, ads="cautious").scenario_id}
    assert plan_uniform("highway-cut-in", 1, 0, ads="cautious",
                        world="follower")[0].batch == "uniform-cautious-follower-seed0"


def test_an_unknown_world_or_one_a_scenario_lacks_is_refused(specs) -> None:
    with pytest.raises(UnknownWorldError, match="known: default, follower"):
        run_spec("highway-cut-in", specs[0].params, 1, world="fog")
    with pytest.raises(UnknownWorldError, match="no variant of unprotected-intersection"):
        plan_uniform("unprotected-intersection", 1, 0, world="follower")


def test_the_follower_starts_behind_the_ego_in_its_lane_and_follows_it(specs) -> None:
    spec = replace(specs[1], world="follower")
    world, cruise = build_world(spec)
    plain, _ = build_world(specs[1])
    assert len(world.npcs) == len(plain.npcs) + 1  # the others as they were, the follower last
    s0 = world.scene()
    ego, fol = 0, len(world.vehicles) - 1
    assert s0.y_m[fol] == pytest.approx(s0.y_m[ego])  # the ego's lane
    assert s0.x_m[ego] - s0.x_m[fol] - 5.0 == pytest.approx(FOLLOWER_HEADWAY_S * cruise)
    assert s0.speed_mps[fol] == s0.speed_mps[ego] == cruise
    assert world.npcs[-1].path.y[0] == pytest.approx(plain.ego.position[1])
    ep = run_episode(spec)
    assert not ep.outcome.collided
    gap = np.array([f.scene.x_m[ego] - f.scene.x_m[fol] - 5.0 for f in ep.frames])
    v_ego = np.array([f.scene.speed_mps[ego] for f in ep.frames])
    v_fol = np.array([f.scene.speed_mps[fol] for f in ep.frames])
    assert gap.min() > 5.0 and gap.max() < 3.0 * FOLLOWER_HEADWAY_S * cruise  # it keeps up …
    assert np.abs(v_fol - v_ego).max() < 3.0  # … at the ego's speed, which holds it up
    assert all(abs(f.scene.y_m[fol] - f.scene.y_m[ego]) < 0.5 for f in ep.frames)


def test_a_needless_hard_brake_gets_the_ego_struck_from_behind_only_with_a_follower(specs) -> None:
    safe = specs[1]
    trigger = Trigger("always", "v", (0.5,))
    plain = run_supervised(safe, _false_alarm, trigger).episode.outcome
    assert not plain.collided  # without a follower a false brake costs nothing here
    spec = replace(safe, world="follower")
    run = run_supervised(spec, _false_alarm, trigger)  # the production fallback, 9 m/s²
    o = run.episode.outcome
    follower = len(run.episode.frames[0].scene.x_m) - 1
    assert o.collided and o.other_actor == follower and o.collision_time_s > BRAKE_AT_S
    hit = next(f.scene for f in run.episode.frames if f.scene.ego_collision)
    assert hit.x_m[follower] < hit.x_m[0]  # from behind
    assert run.states[round(BRAKE_AT_S / DT)].mode == "braking"
    gentle = run_supervised(spec, _false_alarm, trigger, FALLBACKS["comfort"]).episode.outcome
    assert not gentle.collided  # the price depends on the fallback: 6 m/s² leaves it time


def test_a_driver_with_a_reaction_time_acts_on_what_it_saw_that_long_ago() -> None:
    spec = plan_uniform("highway-cut-in", 1, 0)[0]
    world, _ = build_world(spec)
    path = world.npcs[0].path
    late = Npc(world.road, path, 100.0, 20.0, desired_speed_mps=20.0,
               driver=DriverModel(reaction_s=FOLLOWER_REACTION_S))
    prompt = Npc(world.road, path, 100.0, 20.0, desired_speed_mps=20.0)
    frames = round(FOLLOWER_REACTION_S / DT)
    # a standing car appears 20 m ahead: the prompt driver brakes at once, the late one after 1 s
    seen = [(late.longitudinal(20.0, 0.0, DT), prompt.longitudinal(20.0, 0.0, DT))
            for _ in range(frames + 1)]
    assert all(a == 0.0 for a, _ in seen[:frames]) and seen[0][1] < -5.0
    assert seen[frames][0] == seen[0][1]  # the decision it took when it saw it
