"""Ground-truth criticality: TTC-2D and the required deceleration of a scene, which frames
justify an intervention, and the hazardous encounters that ended safely; and how the sweep
judges an intervention with them."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.criticality import (
    Criticality,
    justified_frames,
    safe_encounters,
    scene_risk,
)
from evoeye.evaluation.supervision.sweep import Reference, _changed_command
from evoeye.scene import SceneState
from evoeye.sim.supervisor import SupervisorState


def scene(*actors: tuple[float, float, float, float, float]) -> SceneState:
    """Actors (x, y, heading, speed, accel), ego first, every one 5 m × 2 m."""
    a = np.array(actors, dtype=float)
    n = len(a)
    return SceneState(0.0, np.arange(n), a[:, 0], a[:, 1], a[:, 2], a[:, 3], a[:, 4],
                      np.full(n, 5.0), np.full(n, 2.0), np.zeros(n, bool), False, -1)


def test_a_closing_lead_has_its_ttc_and_drac() -> None:
    # 20 m between centres, 15 m bumper gap, closing at 10 m/s
    ttc, decel = scene_risk(scene((0, 0, 0, 20, 0), (20, 0, 0, 10, 0)))
    assert ttc == pytest.approx(1.5) and decel == pytest.approx(10**2 / (2 * 15))


def test_a_braking_lead_asks_for_the_stop_behind_it() -> None:
    # the lead stops in 10**2 / (2·5) = 10 m: the ego must stop within 15 + 10 m from 20 m/s
    _, decel = scene_risk(scene((0, 0, 0, 20, 0), (20, 0, 0, 10, -5)))
    assert decel == pytest.approx(20**2 / (2 * 25))


def test_the_frame_does_not_matter_only_the_geometry() -> None:
    """The same scene rotated and moved: the same TTC and deceleration."""
    h = 0.7
    c, s = np.cos(h), np.sin(h)
    moved = scene((5, -3, h, 20, 0), (5 + 20 * c, -3 + 20 * s, h, 10, -5))
    assert scene_risk(moved) == pytest.approx(scene_risk(scene((0, 0, 0, 20, 0),
                                                               (20, 0, 0, 10, -5))))


def test_a_car_in_the_next_lane_asks_for_no_braking() -> None:
    ttc, decel = scene_risk(scene((0, 0, 0, 20, 0), (20, 3.5, 0, 10, -5)))
    assert ttc == np.inf and decel == 0.0
    assert scene_risk(scene((0, 0, 0, 20, 0))) == (np.inf, 0.0)  # alone


def test_a_crossing_car_is_critical_by_its_ttc_alone() -> None:
    # a car 15 m ahead and 15 m to the right, driving left at the ego's speed: they meet
    ttc, decel = scene_risk(scene((0, 0, 0, 10, 0), (15, -15, np.pi / 2, 10, 0)))
    assert ttc < 1.5 and decel == 0.0


def test_an_intervention_is_justified_by_the_label_or_a_critical_frame_within_h() -> None:
    label = np.array([0, 0, 0, 0, 0, 0, 1, 1], np.int8)
    critical = np.zeros(10, bool)
    critical[3] = True
    got = justified_frames(label, critical, horizon_frames=2)
    np.testing.assert_array_equal(got, [0, 1, 1, 1, 0, 0, 1, 1])


def test_safe_encounters_are_conflicts_with_nothing_justified() -> None:
    conflict = np.array([0, 1, 1, 0, 0, 1, 1, 1, 0, 1], bool)
    justified = np.array([0, 0, 0, 0, 0, 0, 1, 0, 0, 0], bool)
    assert safe_encounters(conflict, justified) == 2  # frames 1–2 and 9; 5–7 turned critical
    assert safe_encounters(np.zeros(10, bool), justified) == 0


def test_bounds_must_nest() -> None:
    with pytest.raises(ValueError, match="criticality bounds"):
        Criticality(critical_ttc_s=4.0)


def _state(mode: str, ads: float, applied: float) -> SupervisorState:
    return SupervisorState(0.0, 1.0, 0.5, True, True, mode, ads, applied, "t", "v")


def test_an_unneeded_brake_is_false_only_if_it_changed_the_command() -> None:
    ref = Reference(eligible=6, label=np.array([0, 0, 0, 0, 1, 1], np.int8),
                    justified=np.array([0, 0, 1, 1, 1, 1], bool), collision_time_s=0.3,
                    dt_s=0.05)
    assert [ref.judge(k) for k in (0, 2, 4, 6)] == ["unneeded", "justified", "true", "late"]
    assert ref.calm_s == pytest.approx(0.1) and ref.safe_s == pytest.approx(0.2)
    # the ADS brakes harder than the fallback all along: nothing changed, then nominal
    rode_along = [_state("braking", -8.0, -8.0), _state("braking", -8.5, -8.5),
                  _state("nominal", -2.0, -2.0), _state("braking", 0.0, -3.0)]
    assert not _changed_command(rode_along, 0)
    assert _changed_command(rode_along, 3)
    handed_back = [_state("braking", -1.0, -1.0), _state("handback", 0.5, -1.0)]
    assert _changed_command(handed_back, 0)  # the hand-back's bounded rise is the fallback's
