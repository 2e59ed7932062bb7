"""Counterfactual re-simulation: the careful reference driver, alignment with the factual run,
and an oracle that removes a constructed failure."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from evoeye.ads import ADSConfig
from evoeye.ads.messages import ControlCommand
from evoeye.batch import plan_uniform
from evoeye.scene import RoadMap, SceneState
from evoeye.sim.counterfactual import (
    BRAKE_DECEL_MPS2,
    BRAKE_RAMP_S,
    PREDICTION_ITERATIONS,
    REACTION_S,
    VARIANTS,
    CarefulDriver,
    brake_profile,
    careful_driver,
    careful_reaction_time,
    cv_overlap_time,
    explain_run,
    with_module,
)
from evoeye.sim.episode import Episode, Frame, Outcome, RunSpec
from evoeye.sim.runner import SimConfig, run_episode

DT_S = 0.05


def head_on(n_frames: int, gap_m: float = 100.0, v_ego: float = 10.0, v_other: float = 12.0):
    """The ego drives +x at v_ego; actor 1 comes head-on from gap_m ahead at v_other."""
    scenes = []
    for k in range(n_frames):
        t = k * DT_S
        x = np.array([v_ego * t, gap_m - v_other * t])
        scenes.append(SceneState(t, np.array([0, 1]), x, np.zeros(2), np.array([0.0, math.pi]),
                                 np.array([v_ego, v_other]), np.zeros(2), np.full(2, 5.0),
                                 np.full(2, 2.0), np.zeros(2, bool), False, -1))
    return scenes


def test_the_careful_driver_reacts_0_75_s_after_the_cv_futures_first_overlap():
    scenes = head_on(200)
    # the 5 m boxes touch once the centres are 5 m apart: (10 + 12)·(t + τ) ≥ 95, τ ≤ 3 s
    first_overlap = math.ceil((95.0 / 22.0 - 3.0) / DT_S - 1e-9) * DT_S
    assert cv_overlap_time(scenes, partner=1) == pytest.approx(first_overlap)
    episode = Episode(RunSpec("x", (), 0, "x"), RoadMap.empty("x"),
                      Outcome("ok", collided=True, collision_time_s=4.3, other_actor=1), "v",
                      20.0, [Frame(s, None) for s in scenes])
    assert careful_reaction_time(episode) == pytest.approx(first_overlap + REACTION_S)
    assert cv_overlap_time(scenes, partner=5) is None  # no such actor: never


def test_no_overlap_within_the_horizon_means_no_danger_yet():
    assert cv_overlap_time(head_on(20, gap_m=200.0), partner=1) is None  # ≥ 3 s apart


class FixedADS:
    """Stands in for the ADS: always commands +1 m/s² and a fixed steering angle."""

    def __init__(self, accel: float = 1.0) -> None:
        self.accel = accel
        self.config = ADSConfig()

    def step(self, scene):
        cmd = ControlCommand(scene.t_s, 0.3, 0.0, 0.12, self.accel)
        return SimpleNamespace(control=cmd)


@pytest.mark.parametrize("ads_accel", [1.0, -2.0])
def test_the_careful_driver_ramps_its_deceleration_to_7_59_in_0_6_s(ads_accel: float):
    react = 1.0
    driver = CarefulDriver(FixedADS(ads_accel), react_s=react)
    scenes = head_on(60)
    cmds = [driver.step(s).control for s in scenes]
    t = np.array([s.t_s for s in scenes])
    accel = np.array([c.accel_cmd_mps2 for c in cmds])
    assert (accel[t < react - 1e-9] == ads_accel).all()  # the ADS drives until it reacts
    a0 = min(ads_accel, 0.0)
    after = t >= react - 1e-9
    ramp = np.clip((t - react) / BRAKE_RAMP_S, 0.0, 1.0)
    np.testing.assert_allclose(accel[after], (a0 + (-BRAKE_DECEL_MPS2 - a0) * ramp)[after])
    assert accel[t >= react + BRAKE_RAMP_S - 1e-9] == pytest.approx(-BRAKE_DECEL_MPS2)
    assert all(c.steering_rad == 0.12 for c in cmds)  # steering as the ADS commands
    assert brake_profile(0.3) == pytest.approx(-BRAKE_DECEL_MPS2 / 2)


def _same_run(a: Episode, b: Episode) -> None:
    assert len(a.frames) == len(b.frames)
    assert a.outcome == b.outcome
    for fa, fb in zip(a.frames, b.frames, strict=True):
        np.testing.assert_array_equal(fa.scene.x_m, fb.scene.x_m)
        np.testing.assert_array_equal(fa.scene.y_m, fb.scene.y_m)
        assert fa.messages.control == fb.messages.control


def test_a_counterfactual_that_never_acts_differently_reproduces_the_factual_run():
    spec = plan_uniform("unprotected-intersection", 1, 3)[0]
    sim = SimConfig(duration_s=8.0)
    factual = run_episode(spec, sim)
    _same_run(factual, run_episode(spec, sim, driver=careful_driver(None)))
    _same_run(factual, run_episode(spec, sim, driver=with_module("planner", lambda a: a.planner)))
    late = run_episode(spec, sim, driver=careful_driver(7.0))  # reacts at 7 s: same until then
    k = round(7.0 / DT_S)
    _same_run(dataclasses.replace(factual, frames=factual.frames[:k], outcome=late.outcome),
              dataclasses.replace(late, frames=late.frames[:k]))


def test_ground_truth_perception_avoids_collisions_of_a_blind_ads():
    """A blind sensor (0.5 m range): the ADS never brakes for anyone. With the oracle's ground
    truth the same stack must avoid some of those collisions."""
    config = ADSConfig()
    blind = dataclasses.replace(config, sensor=dataclasses.replace(
        config.sensor, lidar_range_m=0.5, radar_range_m=0.5))
    sim = SimConfig(duration_s=10.0)
    collided = avoided = 0
    for spec in plan_uniform("highway-cut-in", 10, 0):
        try:
            ex = explain_run(spec, sim, blind, variants=("oracle_perception",))
        except ValueError:
            continue
        collided += 1
        avoided += not ex.variants[0].collided
    assert collided >= 3
    assert avoided >= 1


def late_sighted() -> ADSConfig:
    """The default stack with sensors that reach only 12 m: it collides whatever the world's
    tuning, so the explanation machinery is tested independently of the collision rate."""
    config = ADSConfig()
    return dataclasses.replace(config, sensor=dataclasses.replace(
        config.sensor, lidar_range_m=12.0, radar_range_m=12.0))


def first_collision(scenario: str, config: ADSConfig, sim: SimConfig) -> RunSpec:
    for spec in plan_uniform(scenario, 40, 7):
        if run_episode(spec, sim, config).outcome.collided:
            return spec
    raise AssertionError(f"no {scenario} run of 40 collides with this stack")


def test_every_variant_of_a_collision_run():
    sim, config = SimConfig(duration_s=10.0), late_sighted()
    spec = first_collision("unprotected-intersection", config, sim)
    ex = explain_run(spec, sim, config)
    assert [v.variant for v in ex.variants] == list(VARIANTS)
    by = {v.variant: v for v in ex.variants}
    assert 1 <= by["oracle_prediction"].simulations <= PREDICTION_ITERATIONS
    assert by["careful_driver"].react_s is not None
    for v in ex.variants:
        assert v.collided == (v.collision_time_s is not None)
        assert (v.min_distance_m == 0.0) or not v.collided


def test_a_run_that_does_not_collide_is_refused():
    sim = SimConfig(duration_s=3.0)
    spec = next(s for s in plan_uniform("highway-cut-in", 20, 1)
                if not run_episode(s, sim).outcome.collided)
    with pytest.raises(ValueError, match="does not collide"):
        explain_run(spec, sim)


def test_root_causes_are_the_modules_whose_oracle_avoids_it_in_pipeline_order():
    from evoeye.sim.counterfactual import ORACLES, VariantResult, avoided_by

    assert ORACLES == ("oracle_perception", "oracle_prediction", "oracle_planning",
                       "oracle_control")
    results = [VariantResult(v, collided, None, None, False) for v, collided in (
        ("oracle_control", False), ("careful_driver", False), ("oracle_perception", False),
        ("oracle_planning", True))]
    assert avoided_by(results) == ["perception", "control"]  # not the careful driver
    assert avoided_by([]) == []
