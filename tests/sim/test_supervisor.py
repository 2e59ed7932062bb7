"""The supervisor: the unsupervised run until its first alarm, then the fallback's profile;
thresholds share a simulation while they decide alike; same inputs, same run."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from evoeye.ads import ADSConfig
from evoeye.ads.messages import ControlCommand
from evoeye.batch import plan_uniform
from evoeye.log.synthetic import synthetic_episode
from evoeye.sim.runner import run_episode
from evoeye.sim.supervisor import (
    FALLBACKS,
    FallbackConfig,
    SupervisedDriver,
    Trigger,
    first_engagements,
    run_supervised,
)

DT = 0.05


class ScriptedADS:
    """Stands in for the ADS: synthetic messages whose control asks for `accel[k]`."""

    def __init__(self, accel: list[float]) -> None:
        self.config = ADSConfig()
        self.accel = accel
        self.frames = synthetic_episode(len(accel), seed=3, n_obstacles=2).frames
        self.k = 0

    def step(self, scene):
        msgs = self.frames[self.k].messages
        c = msgs.control
        msgs.control = ControlCommand(c.t_s, 0.0, 0.0, 0.01, self.accel[self.k])
        self.k += 1
        return msgs


def drive(scores: list[float], thresholds: tuple[float, ...], *, ads_accel: float = 1.0,
          speed_mps: float | list[float] = 20.0, config: FallbackConfig | None = None,
          consecutive: int = 1) -> SupervisedDriver:
    """Step a SupervisedDriver through `scores` (the risk of each frame)."""
    n = len(scores)
    ads = ScriptedADS([ads_accel] * n)
    it = iter(scores)
    driver = SupervisedDriver(ads, lambda m: next(it), Trigger("t", "v", thresholds, consecutive),
                              config or FallbackConfig(), DT)
    speeds = [speed_mps] * n if np.isscalar(speed_mps) else speed_mps
    for f, v in zip(ads.frames, speeds, strict=True):
        f.scene.speed_mps[0] = v
        driver.step(f.scene)
    return driver


def test_the_fallback_brakes_after_its_onset_at_a_bounded_jerk_to_its_deceleration() -> None:
    config = FallbackConfig(decel_mps2=6.0, jerk_mps3=10.0, onset_s=0.1, hold_s=10.0)
    d = drive([0.0] * 5 + [0.9] * 40, (0.5,), config=config)
    modes = [s.mode for s in d.states]
    assert modes[:5] == ["nominal"] * 5 and set(modes[5:]) == {"braking"}
    applied = np.array([s.accel_cmd_mps2 for s in d.states])
    assert (applied[:7] == 1.0).all()  # before the alarm, and during the brakes' dead time
    ramp = applied[7:]
    # the throttle is cut, then the deceleration grows by jerk·dt per frame to its hold
    np.testing.assert_allclose(ramp[:6], [-0.5, -1.0, -1.5, -2.0, -2.5, -3.0])
    assert np.all(np.diff(ramp) >= -config.jerk_mps3 * DT - 1e-12)
    assert ramp.min() == -6.0 and (ramp[-10:] == -6.0).all()
    assert all(s.ads_accel_mps2 == 1.0 for s in d.states)
    assert [s.alarm for s in d.states] == [False] * 5 + [True] * 40


def test_the_production_fallback_is_the_default_and_brakes_at_9_reached_at_30_per_s() -> None:
    assert FallbackConfig() == FALLBACKS["production"]
    d = drive([0.0] * 5 + [0.9] * 20, (0.5,), config=replace(FallbackConfig(), hold_s=10.0))
    applied = np.array([s.accel_cmd_mps2 for s in d.states])
    assert (applied[:7] == 1.0).all()  # the same dead time: 0.1 s
    np.testing.assert_allclose(applied[7:14], [-1.5, -3.0, -4.5, -6.0, -7.5, -9.0, -9.0])
    assert (applied[12:] == -9.0).all()  # 9 m/s² in 0.3 s, then held
    comfort = drive([0.0] * 5 + [0.9] * 20, (0.5,), config=FALLBACKS["comfort"])
    assert min(s.accel_cmd_mps2 for s in comfort.states) == -6.0  # one option away


def test_a_staged_fallback_pauses_at_its_stage_then_brakes_fully_within_the_jerk_bound() -> None:
    config = replace(FallbackConfig(onset_s=0.0, hold_s=10.0), stage_decel_mps2=4.0, stage_s=0.5)
    d = drive([0.9] * 30, (0.5,), config=config)
    applied = np.array([s.accel_cmd_mps2 for s in d.states])
    # the stage: −1.5, −3, then −4 held until 0.5 s (10 frames) after the ramp's start …
    np.testing.assert_allclose(applied[:10], [-1.5, -3.0] + [-4.0] * 8)
    # … then on at 30 m/s³ to the full 9 m/s²
    np.testing.assert_allclose(applied[10:15], [-5.5, -7.0, -8.5, -9.0, -9.0])
    steps = np.diff(np.concatenate([[0.0], applied]))  # from the throttle cut (at once)
    assert steps.min() >= -config.jerk_mps3 * DT - 1e-12  # no step harder than the jerk limit
    unstaged = drive([0.9] * 30, (0.5,), config=replace(config, stage_decel_mps2=0.0,
                                                         stage_s=0.0))
    late = [s.accel_cmd_mps2 for s in unstaged.states].index(-9.0)
    assert list(applied).index(-9.0) == late + 8  # the stage costs its time at 4 instead of 9


def test_the_ads_stronger_aeb_wins_over_the_stage_and_the_ramp() -> None:
    config = replace(FallbackConfig(onset_s=0.0, hold_s=10.0), stage_decel_mps2=4.0, stage_s=1.0)
    ads = ScriptedADS([1.0] * 4 + [-8.0] * 26)  # the ADS's AEB fires during the stage
    driver = SupervisedDriver(ads, lambda m: 0.9, Trigger("t", "v", (0.5,)), config, DT)
    commands = []
    for f in ads.frames:
        f.scene.speed_mps[0] = 20.0
        commands.append(driver.step(f.scene).control)
    applied = [c.accel_cmd_mps2 for c in commands]
    assert applied[:4] == [-1.5, -3.0, -4.0, -4.0]  # the stage, while the ADS asks for +1
    assert applied[4:22] == [-8.0] * 18  # the AEB's 8 beats the stage's 4 and the ramp's 5.5, 7
    assert applied[22:] == [-8.5] + [-9.0] * 7  # the ramp beyond it: the tyres' 9
    assert all(0.0 <= c.brake <= 1.0 for c in commands)  # 1: the ADS's full brake or more
    assert commands[-1].brake == 1.0 and commands[0].brake == pytest.approx(1.5 / 8.0)


def test_the_fallback_never_brakes_less_than_the_ads_nor_reverses() -> None:
    comfort = replace(FALLBACKS["comfort"], onset_s=0.0)
    d = drive([0.9] * 30, (0.5,), ads_accel=-8.0, config=comfort)
    assert all(s.accel_cmd_mps2 == -8.0 for s in d.states)  # the ADS's AEB stays in force
    slowing = [2.0, 1.0, 0.2, 0.05, 0.0, 0.0]
    d = drive([0.9] * 6, (0.5,), ads_accel=-8.0, speed_mps=slowing, config=comfort)
    applied = [s.accel_cmd_mps2 for s in d.states]
    assert applied[:3] == [-8.0, -8.0, -0.2 / DT]  # never more than stops the ego this step
    assert [s.mode for s in d.states] == ["braking"] * 3 + ["holding"] * 3
    assert applied[3:] == [-0.05 / DT, 0.0, 0.0]


def test_it_hands_back_after_the_hold_time_rising_at_the_jerk_limit() -> None:
    config = FallbackConfig(decel_mps2=6.0, jerk_mps3=10.0, onset_s=0.0, hold_s=0.5)
    scores = [0.9] * 20 + [0.1] * 40
    d = drive(scores, (0.5,), ads_accel=2.0, config=config)
    modes = [s.mode for s in d.states]
    release = 20 + round(0.5 / DT) - 1  # the 10th frame at or below the threshold
    assert modes[:release] == ["braking"] * release
    assert modes[release] == "handback"
    applied = np.array([s.accel_cmd_mps2 for s in d.states])
    back = applied[release - 1:]
    assert np.all(np.diff(back) <= config.jerk_mps3 * DT + 1e-12)
    assert modes[-1] == "nominal" and applied[-1] == 2.0
    assert modes.index("nominal", release) == release + 15  # −6 to +2 at 0.5 per frame


def test_thresholds_share_a_run_while_their_decisions_agree() -> None:
    scores = [0.0] * 10 + [0.6] * 5 + [0.8] * 5 + [0.0] * 30
    d = drive(scores, (0.5, 0.55, 0.7, 0.95), config=FallbackConfig(hold_s=0.5))
    # 0.5 and 0.55 engage at frame 10 together; 0.7 waits (fork at 10), 0.95 never alarms
    assert d.thresholds == (0.5, 0.55)
    assert [(f.frame, f.thresholds) for f in d.forks] == [(10, (0.7, 0.95))]
    again = drive(scores, (0.7, 0.95), config=FallbackConfig(hold_s=0.5))
    assert [(f.frame, f.thresholds) for f in again.forks] == [(15, (0.95,))]
    assert first_engagements(scores, (0.5, 0.55, 0.7, 0.95)) == [10, 10, 15, None]


def test_first_engagements_need_k_consecutive_frames() -> None:
    scores = [0.9, 0.1, 0.9, 0.9, 0.1, 0.9, 0.9, 0.9]
    assert first_engagements(scores, (0.5,), 1) == [0]
    assert first_engagements(scores, (0.5,), 2) == [3]
    assert first_engagements(scores, (0.5,), 3) == [7]
    assert first_engagements(scores, (0.5,), 4) == [None]
    d = drive(scores, (0.5,), consecutive=3)
    assert [s.mode for s in d.states].index("braking") == 7


def test_bad_fallback_and_trigger_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="decel"):
        FallbackConfig(decel_mps2=0.0)
    with pytest.raises(ValueError, match="at least 1"):
        Trigger("t", "v", (0.5,), consecutive=0)
    with pytest.raises(ValueError, match="threshold"):
        Trigger("t", "v", ())


@pytest.fixture(scope="module")
def spec():
    return plan_uniform("highway-cut-in", 2, 0)[1]


def _late_alarm(m) -> float:
    return 1.0 if m.localization.t_s >= 5.0 - 1e-9 else 0.0


def test_a_supervised_run_is_the_unsupervised_run_until_its_first_alarm(spec) -> None:
    plain = run_episode(spec)
    run = run_supervised(spec, _late_alarm, Trigger("t", "v", (0.5, 2.0)))
    assert run.thresholds == (0.5,) and [f.frame for f in run.forks] == [100]
    onset = round(FallbackConfig().onset_s / DT)
    for k, (a, b) in enumerate(zip(plain.frames, run.episode.frames, strict=False)):
        same = (np.array_equal(a.scene.x_m, b.scene.x_m)
                and np.array_equal(a.messages.plan.speed_mps, b.messages.plan.speed_mps)
                and a.messages.control == b.messages.control)
        assert same == (k < 100 + onset), k
    assert len(run.states) == len(run.episode.frames)
    speed = [f.scene.speed_mps[0] for f in run.episode.frames]
    assert speed[140] < speed[100] - 5.0  # it brakes
    assert run.states[100].mode == "braking" and run.states[99].mode == "nominal"


def test_same_inputs_same_supervised_run(spec) -> None:
    a = run_supervised(spec, _late_alarm, Trigger("t", "v", (0.5,)))
    b = run_supervised(spec, _late_alarm, Trigger("t", "v", (0.5,)))
    assert a.states == b.states and a.episode.outcome == b.episode.outcome
    assert all(np.array_equal(x.scene.x_m, y.scene.x_m)
               for x, y in zip(a.episode.frames, b.episode.frames, strict=True))


def test_fallbacks_by_name_with_changes_and_their_bounds() -> None:
    from evoeye.sim.supervisor import fallback_with

    assert fallback_with("comfort") == FallbackConfig(decel_mps2=6.0, jerk_mps3=10.0)
    assert fallback_with("comfort", decel_mps2=7.0, jerk_mps3=None).jerk_mps3 == 10.0
    assert fallback_with(stage_decel_mps2=4.0, stage_s=0.5).staged
    with pytest.raises(ValueError, match="known: production, comfort"):
        fallback_with("gentle")
    with pytest.raises(ValueError, match="tyres"):
        FallbackConfig(decel_mps2=9.5)  # no car brakes harder than the world lets it
    for stage in ({"stage_s": 0.5}, {"stage_decel_mps2": 4.0}, {"stage_decel_mps2": 9.0,
                                                                "stage_s": 0.5}):
        with pytest.raises(ValueError, match="stage"):
            FallbackConfig(**stage)
    # a fallback without a stage records no stage: its record is the one written before stages
    assert FALLBACKS["comfort"].to_dict() == {"decel_mps2": 6.0, "jerk_mps3": 10.0,
                                              "onset_s": 0.1, "hold_s": 1.0,
                                              "standstill_mps": 0.1}
    staged = replace(FallbackConfig(), stage_decel_mps2=4.0, stage_s=0.5)
    assert FallbackConfig(**staged.to_dict()) == staged
