"""RSS baseline: ad-rss's safe distances equal the RSS formulas; too close is unsafe."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.baselines.rss import (
    LAT_OTHER_LEFT,
    LON_EGO_FOLLOWS,
    LON_ONCOMING,
    LON_OTHER_FOLLOWS,
    AdRss,
    RSSMonitor,
    RssParams,
)
from evoeye.evaluation.monitors import BASELINES
from evoeye.monitor.protocol import Monitor

P = RssParams()  # rho 1 s, a_max 3.5, b_min 4, b_max 8, b_min_correct 3, lat 0.2 / 0.8, mu 0.1


def same_direction_m(v_rear: float, v_front: float, p: RssParams = P) -> float:
    """RSS paper, Definition 1 (safe longitudinal distance, same direction)."""
    rho, a, bmin, bmax = p.response_time_s, p.accel_max_mps2, p.brake_min_mps2, p.brake_max_mps2
    d = (v_rear * rho + a * rho**2 / 2 + (v_rear + rho * a) ** 2 / (2 * bmin)
         - v_front**2 / (2 * bmax))
    return max(d, 0.0)


def opposite_direction_m(v_correct: float, v_oncoming: float, p: RssParams = P) -> float:
    """RSS paper, Definition 4 (opposite directions, the first car in its correct lane)."""
    rho, a = p.response_time_s, p.accel_max_mps2
    v1r, v2r = v_correct + rho * a, v_oncoming + rho * a
    return ((v_correct + v1r) / 2 * rho + v1r**2 / (2 * p.brake_min_correct_mps2)
            + (v_oncoming + v2r) / 2 * rho + v2r**2 / (2 * p.brake_min_mps2))


def lateral_m(v_left_to_right: float, p: RssParams = P) -> float:
    """RSS paper, Definition 6, the ego (right) keeping still laterally."""
    rho, a, b = p.response_time_s, p.lat_accel_max_mps2, p.lat_brake_min_mps2
    v1r, v2r = v_left_to_right + rho * a, 0.0 - rho * a
    d = (v_left_to_right + v1r) / 2 * rho + (v1r**2 / (2 * b) if v1r > 0 else 0.0)
    d -= (0.0 + v2r) / 2 * rho - v2r**2 / (2 * b)
    return max(d + p.lateral_fluctuation_margin_m, 0.0)


@pytest.mark.parametrize(("v_rear", "v_front"), [(20.0, 10.0), (10.0, 20.0), (30.0, 30.0)])
def test_same_direction_distance_is_the_rss_formula(v_rear: float, v_front: float) -> None:
    lib = AdRss(P, P)
    assert lib.lon_same_direction_m(v_rear, v_front, ego_follows=True) == pytest.approx(
        same_direction_m(v_rear, v_front), abs=1e-3)
    assert lib.lon_same_direction_m(v_rear, v_front, ego_follows=False) == pytest.approx(
        same_direction_m(v_rear, v_front), abs=1e-3)
    assert lib.lon_same_direction_m(20.0, 10.0, ego_follows=True) == pytest.approx(84.53125)


def test_opposite_and_lateral_distances_are_the_rss_formulas() -> None:
    lib = AdRss(P, P)
    assert lib.lon_opposite_direction_m(10.0, 10.0) == pytest.approx(76.65625, abs=1e-3)
    assert lib.lon_opposite_direction_m(15.0, 5.0) == pytest.approx(
        opposite_direction_m(15.0, 5.0), abs=1e-3)
    for v in (0.0, 0.5, -0.5):
        assert lib.lateral_m(v, other_is_left=True) == pytest.approx(lateral_m(v), abs=1e-3)


def test_other_dynamics_change_the_library_answer_as_the_formula_says() -> None:
    quick = RssParams(response_time_s=0.5, brake_min_mps2=6.0)
    lib = AdRss(quick, P)  # the ego follows, so the ego's dynamics matter
    assert lib.lon_same_direction_m(20.0, 10.0, ego_follows=True) == pytest.approx(
        same_direction_m(20.0, 10.0, quick), abs=1e-3)


def test_the_library_checks_its_input() -> None:
    lib = AdRss(RssParams(response_time_s=-1.0), P)
    with pytest.raises(ValueError, match="ad-rss"):
        lib.lon_same_direction_m(20.0, 10.0, ego_follows=True)


def test_monitor_distances_are_the_library_ones_at_grid_speeds() -> None:
    m = RSSMonitor(speed_grid_mps=0.05)
    kinds = np.array([LON_EGO_FOLLOWS, LON_OTHER_FOLLOWS, LON_ONCOMING, LAT_OTHER_LEFT])
    got = m.safe_distances_m(kinds, np.array([20.01, 20.0, 10.0, 0.0]),
                             np.array([9.99, 10.0, 10.0, 0.5]))
    expected = [same_direction_m(20.0, 10.0), same_direction_m(20.0, 10.0),
                opposite_direction_m(10.0, 10.0), lateral_m(0.5)]
    assert got == pytest.approx(expected, abs=1e-3)


def test_too_close_follower_is_unsafe_and_far_one_safe(windows_of, obs) -> None:
    m = RSSMonitor()
    safe_m = same_direction_m(20.0, 10.0)  # 84.5 m
    w = windows_of(
        [[obs(30.0 + 5.0, 0.0, dvx_mps=-10.0)],  # ego at 20 m/s, 30 m behind a car at 10
         [obs(120.0 + 5.0, 0.0, dvx_mps=-10.0)],  # 120 m behind it
         [obs(0.0, 4.0)],  # alongside in the next lane, no lateral motion
         [obs(-30.0 - 5.0, 0.0, dvx_mps=+10.0)]],  # a car at 30 m/s 30 m behind the ego
        ego_speed_mps=[20.0, 20.0, 20.0, 20.0],
    )
    risk = m.score(w)
    assert risk[0] == pytest.approx(safe_m / (safe_m + 30.0), abs=1e-3) and risk[0] > 0.5
    assert risk[1] == pytest.approx(safe_m / (safe_m + 120.0), abs=1e-3) and risk[1] < 0.5
    assert risk[2] < 0.5  # laterally 2 m apart, more than the lateral safe distance
    assert risk[3] == pytest.approx(same_direction_m(30.0, 20.0) / (same_direction_m(30.0, 20.0)
                                    + 30.0), abs=1e-3)


def test_a_car_swerving_in_from_the_next_lane_raises_the_risk(windows_of, obs) -> None:
    m = RSSMonitor()
    w = windows_of([[obs(8.0, 3.0, dvy_mps=0.0)], [obs(8.0, 3.0, dvy_mps=-1.5)]],
                   ego_speed_mps=[20.0, 20.0])
    still, swerving = m.score(w)
    assert swerving > 0.5 > still


def test_is_a_monitor() -> None:
    assert isinstance(RSSMonitor(), Monitor) and RSSMonitor().version.startswith("rss-")


def test_the_rss_2s_variant_gives_other_vehicles_carlas_2s_response_time(windows_of,
                                                                        obs) -> None:
    m = BASELINES["rss-2s"](None, "s", None)
    assert m.name == "rss-2s" and m.other.response_time_s == 2.0 and m.ego == P
    assert m.version != RSSMonitor().version
    slow = RssParams(response_time_s=2.0)
    w = windows_of([[obs(-30.0 - 5.0, 0.0, dvx_mps=+10.0)]], ego_speed_mps=[20.0])  # followed
    safe_m = same_direction_m(30.0, 20.0, slow)  # the follower is the other vehicle: its 2 s
    assert m.score(w)[0] == pytest.approx(safe_m / (safe_m + 30.0), abs=1e-3)
    assert m.score(w)[0] > RSSMonitor().score(w)[0]
