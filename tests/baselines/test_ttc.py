"""TTC baseline: exact times to collision on hand-placed obstacles, and the risk map."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.baselines.ttc import TTCMonitor, ttc_risk
from evoeye.monitor.protocol import Monitor

HALF_LENGTHS_M = 5.0  # (ego 5 m + obstacle 5 m) / 2: centre distance = gap + 5 m


def test_obstacle_20m_ahead_closing_at_10mps_gives_2s_and_its_risk(windows_of, obs) -> None:
    w = windows_of([[obs(20.0 + HALF_LENGTHS_M, 0.0, dvx_mps=-10.0)]])
    m = TTCMonitor(tau_s=1.0)
    assert m.ttc_s(w)[0] == pytest.approx(2.0)
    assert m.score(w)[0] == pytest.approx(1.0 / 3.0)  # 1 / (1 + 2 s / 1 s)
    assert TTCMonitor(tau_s=2.0).score(w)[0] == pytest.approx(0.5)


def test_obstacles_out_of_the_corridor_or_not_closing_carry_no_risk(windows_of, obs) -> None:
    w = windows_of([
        [obs(25.0, 4.0, dvx_mps=-10.0)],  # next lane (4 m to the left), closing fast
        [obs(25.0, -4.0, dvx_mps=-10.0)],  # next lane on the right
        [obs(25.0, 0.0, dvx_mps=+3.0)],  # ahead in the lane, pulling away
        [],  # nothing perceived
    ])
    m = TTCMonitor()
    assert np.isinf(m.ttc_s(w)).all()
    assert m.score(w).tolist() == [0.0, 0.0, 0.0, 0.0]


def test_corridor_edge_follows_the_half_widths_plus_margin(windows_of, obs) -> None:
    m = TTCMonitor(corridor_margin_m=0.3)  # (2 + 2) / 2 + 0.3 = 2.3 m
    w = windows_of([[obs(25.0, 2.29, dvx_mps=-5.0)], [obs(25.0, 2.31, dvx_mps=-5.0)]])
    ttc = m.ttc_s(w)
    assert ttc[0] == pytest.approx(4.0) and np.isinf(ttc[1])


def test_minimum_over_obstacles_rear_closing_and_contact(windows_of, obs) -> None:
    w = windows_of([
        [obs(45.0, 0.0, dvx_mps=-10.0), obs(15.0, 0.5, dvx_mps=-5.0)],  # 4 s and 2 s
        [obs(-15.0, 0.0, dvx_mps=+5.0)],  # behind, 10 m gap, closing at 5 m/s
        [obs(4.0, 0.0, dvx_mps=+1.0)],  # footprints overlap: TTC 0 whatever the speed
    ])
    m = TTCMonitor()
    assert m.ttc_s(w).tolist() == pytest.approx([2.0, 2.0, 0.0])
    assert m.score(w)[2] == 1.0


def test_risk_is_monotone_and_bounded() -> None:
    ttc = np.array([0.0, 0.5, 1.0, 3.0, 10.0, np.inf])
    risk = ttc_risk(ttc, 1.0)
    assert (np.diff(risk) < 0).all() and risk[0] == 1.0 and risk[-1] == 0.0


def test_is_a_monitor_with_a_parameter_version() -> None:
    assert isinstance(TTCMonitor(), Monitor)
    assert TTCMonitor().version == TTCMonitor().version != TTCMonitor(tau_s=2.0).version
