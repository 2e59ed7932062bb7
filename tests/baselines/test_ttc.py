"""TTC baselines (corridor and 2-D): exact times to collision on hand-placed obstacles, a
stepped box-overlap brute force, and the risk map."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.baselines.ttc import EGO_LENGTH_M, EGO_WIDTH_M, TTC2DMonitor, TTCMonitor, ttc_risk
from evoeye.boxes import box_corners, box_gaps
from evoeye.evaluation.monitors import BASELINES
from evoeye.monitor.protocol import Monitor
from evoeye.store.features import PERCEPTION_FEATURES

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


# -- TTC-2D ---------------------------------------------------------------------------------------
def _rows(dx, dy, heading, dvx, dvy, length, width) -> np.ndarray:
    """(N, 9) perception rows (ego frame) with any relative heading."""
    cols = {"dx_m": dx, "dy_m": dy, "cos_dheading": np.cos(heading),
            "sin_dheading": np.sin(heading), "dvx_mps": dvx, "dvy_mps": dvy,
            "length_m": length, "width_m": width, "confidence": np.ones_like(dx)}
    return np.stack([np.asarray(cols[k], np.float32) for k in PERCEPTION_FEATURES], axis=-1)


def test_ttc_2d_equals_the_corridor_ttc_in_the_same_lane(windows_of) -> None:
    rng = np.random.default_rng(0)
    n = 200
    dx = rng.choice([-1, 1], n) * rng.uniform(6.0, 80.0, n)
    rows = _rows(dx, np.zeros(n), np.zeros(n), rng.uniform(-15, 15, n), np.zeros(n),
                 rng.uniform(4.0, 12.0, n), np.full(n, 2.0))
    w = windows_of([[r] for r in rows])
    corridor, two_d = TTCMonitor().ttc_s(w), TTC2DMonitor().ttc_s(w)
    assert np.isfinite(corridor).sum() > 50  # closing and opening cases both present
    np.testing.assert_allclose(two_d, corridor, rtol=1e-5)


def test_ttc_2d_sees_the_cut_in_and_the_crossing_the_corridor_misses(windows_of) -> None:
    w = windows_of([
        [_rows([8.0], [3.5], [0.2], [-2.0], [-1.5], [5.0], [2.0])[0]],  # cutting in, angled
        [_rows([20.0], [-15.0], [np.pi / 2], [-10.0], [10.0], [5.0], [2.0])[0]],  # crossing
    ])
    corridor, two_d = TTCMonitor().ttc_s(w), TTC2DMonitor().ttc_s(w)
    assert np.isinf(corridor).all() and np.isfinite(two_d).all()
    # crossing from the right at 10 m/s, the ego closing 10 m/s on it: its box meets the ego's
    # when the x gap 20 − (5 + 2)/2 = 16.5 m and the y gap 15 − (5 + 2)/2 = 11.5 m both close
    assert two_d[1] == pytest.approx(16.5 / 10.0)
    assert TTC2DMonitor().score(w)[1] == pytest.approx(1.0 / (1.0 + 1.65))


def test_ttc_2d_agrees_with_a_stepped_box_overlap_on_random_frames(windows_of) -> None:
    """Eight random obstacles per frame (some slots empty): the monitor's TTC-2D is never later
    than the first 20 Hz step at which any obstacle's box overlaps the ego's, and less than one
    step earlier — unless a box only grazes the ego's between two steps, which is rare and
    checked at the exact time."""
    rng = np.random.default_rng(1)
    frames, n_slots, dt_s = 400, 8, 0.05
    rows = _rows(rng.uniform(-50, 50, (frames, n_slots)), rng.uniform(-20, 20, (frames, n_slots)),
                 rng.uniform(-np.pi, np.pi, (frames, n_slots)),
                 rng.uniform(-20, 20, (frames, n_slots)), rng.uniform(-8, 8, (frames, n_slots)),
                 rng.uniform(3.5, 12, (frames, n_slots)), rng.uniform(1.6, 2.6, (frames, n_slots)))
    present = rng.random((frames, n_slots)) < 0.7
    w = windows_of([list(r[m]) for r, m in zip(rows, present, strict=True)])
    ttc = TTC2DMonitor().ttc_s(w)
    p = rows.astype(np.float64).reshape(-1, rows.shape[-1])[present.reshape(-1)]
    ego = box_corners(*(np.zeros((1, len(p))) + [[0.0], [0.0], [0.0], [EGO_LENGTH_M],
                                                    [EGO_WIDTH_M]]))
    other = box_corners(p[:, 0], p[:, 1], np.arctan2(p[:, 3], p[:, 2]), p[:, 6], p[:, 7])
    frame_of = np.repeat(np.arange(frames), present.sum(axis=1))
    first = np.full(frames, np.inf)
    for t in np.arange(0.0, 6.0 + 1e-9, dt_s)[::-1]:  # latest first: the earliest step wins
        hit = box_gaps(ego, other + (p[:, 4:6] * t)[:, None, :]) <= 0.0
        first[np.unique(frame_of[hit])] = t
    seen = np.isfinite(first)
    assert seen.sum() > 100
    assert (first[seen] - ttc[seen] >= -1e-6).all()  # never later than the steps
    graze = ttc < 6.0 - dt_s  # ≥ one step earlier than the steps, or seen by none of them
    graze[seen] = first[seen] - ttc[seen] >= dt_s - 1e-6
    assert graze.sum() <= 0.02 * frames
    for f in np.flatnonzero(graze):  # a box touches the ego's at the exact time
        mine = frame_of == f
        at = other[mine] + (p[mine, 4:6] * ttc[f])[:, None, :]
        assert box_gaps(ego[mine], at).min() < 1e-6


def test_ttc_2d_is_a_registered_monitor_with_a_parameter_version() -> None:
    assert isinstance(TTC2DMonitor(), Monitor)
    assert TTC2DMonitor().version.startswith("ttc2d-")
    assert TTC2DMonitor().version == TTC2DMonitor().version != TTC2DMonitor(tau_s=2.0).version
    assert isinstance(BASELINES["ttc-2d"](None, "s", None), TTC2DMonitor)
