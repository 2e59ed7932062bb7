"""A collision's mechanism from the ground truth: a braking lead, a slow lead, a cut-in, a
crossing car, a car from behind."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evoeye.evaluation.mechanism import MECHANISMS, mechanism
from evoeye.scene import RoadMap, SceneState
from evoeye.sim.episode import Episode, Frame, Outcome, RunSpec

RATE_HZ, CONTACT = 20.0, 160  # contact 8 s in


def episode(partner, *, collided: bool = True) -> Episode:
    """Ego at x = 20·t along +x; the partner at partner(t) = (x, y, heading, accel)."""
    frames = []
    for k in range(CONTACT + 1):
        t = k / RATE_HZ
        x, y, h, a = partner(t)
        hit = collided and k == CONTACT
        frames.append(Frame(SceneState(
            t, np.array([0, 7]), np.array([20.0 * t, x]), np.array([0.0, y]),
            np.array([0.0, h]), np.array([20.0, 15.0]), np.array([0.0, a]),
            np.full(2, 5.0), np.full(2, 2.0), np.array([hit, hit]), hit, 7 if hit else -1),
            None))
    spec = RunSpec("highway-cut-in", (), 0, "x")
    outcome = Outcome("ok", collided=collided, collision_time_s=CONTACT / RATE_HZ if collided
                      else None, other_actor=7 if collided else None, duration_s=8.0)
    return Episode(spec, RoadMap.empty("highway-cut-in"), outcome, "0", RATE_HZ, frames)


T_C = CONTACT / RATE_HZ


def test_a_lead_that_brakes_ahead_of_the_ego() -> None:
    m = mechanism(episode(lambda t: (20.0 * t + 4.5, 0.0, 0.0, -5.0 if t > T_C - 4.42 else 0.0)))
    assert m.kind == "braking-lead" and m.partner_min_accel_mps2 == -5.0
    assert m.braking_onset_s == pytest.approx(4.4)  # its first braking frame, 4.4 s before


def test_a_slow_lead_never_brakes() -> None:
    assert mechanism(episode(lambda t: (20.0 * t + 4.5, 0.3, 0.0, 0.0))).kind == "slow-lead"


def test_a_car_that_came_in_from_the_side_is_a_cut_in() -> None:
    def partner(t: float):
        y = 3.5 if t < T_C - 1.5 else 3.5 * (T_C - t) / 1.5  # into the lane over 1.5 s
        return 20.0 * t + 4.5, y, 0.0, 0.0
    assert mechanism(episode(partner)).kind == "cut-in"


def test_a_crossing_car_and_a_car_from_behind() -> None:
    assert mechanism(episode(lambda t: (20.0 * T_C + 2, -3.0 + (t - T_C) * 10, math.pi / 2,
                                        0.0))).kind == "crossing"
    assert mechanism(episode(lambda t: (20.0 * t - 4.8, 0.0, 0.0, 1.0))).kind == \
        "struck-from-behind"


def test_no_collision_no_mechanism() -> None:
    assert mechanism(episode(lambda t: (20.0 * t + 30, 0.0, 0.0, 0.0), collided=False)) is None
    assert set(MECHANISMS) >= {"braking-lead", "cut-in", "crossing"}
