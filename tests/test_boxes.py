"""Oriented rectangles: the exact first-contact time of two moving boxes against a brute-force
overlap check stepped in time, and on cases with a known answer."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.boxes import box_corners, box_gap_bound, box_gaps, first_contact_s

DT_S = 0.05  # the brute force's time step (the ADS's 20 Hz)
HORIZON_S = 8.0


def _box(x, y, heading=0.0, length=4.8, width=2.0) -> np.ndarray:
    return box_corners(*(np.atleast_1d(np.asarray(v, float)) for v in
                         (x, y, heading, length, width)))


def _random_states(rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
    """Ego at the origin heading +x; another box around it with any heading, size and relative
    velocity (highway to intersection speeds), half of them heading roughly for the ego."""
    x, y = rng.uniform(-40, 40, n), rng.uniform(-25, 25, n)
    vx, vy = rng.uniform(-25, 25, n), rng.uniform(-15, 15, n)
    aimed, arrive_s = rng.random(n) < 0.5, rng.uniform(0.5, 8.0, n)
    return {"x": x, "y": y, "h": rng.uniform(-np.pi, np.pi, n),
            "length": rng.uniform(3.5, 12.0, n), "width": rng.uniform(1.6, 2.6, n),
            "vx": np.where(aimed, -x / arrive_s + rng.normal(0, 2, n), vx),
            "vy": np.where(aimed, -y / arrive_s + rng.normal(0, 2, n), vy)}


def _random_scene(seed: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ego, other) corners (n, 4, 2) and the other's relative velocity (n, 2)."""
    s = _random_states(np.random.default_rng(seed), n)
    other = box_corners(s["x"], s["y"], s["h"], s["length"], s["width"])
    return np.broadcast_to(_box(0.0, 0.0), (n, 4, 2)), other, np.stack([s["vx"], s["vy"]], -1)


def test_first_contact_agrees_with_a_stepped_brute_force_within_one_step() -> None:
    n = 3000
    ego, other, v = _random_scene(0, n)
    exact = first_contact_s(ego, other, v)
    times = np.arange(0.0, HORIZON_S + 1e-9, DT_S)
    hit = np.stack([box_gaps(ego, other + (v * t)[:, None, :]) <= 0.0 for t in times])  # (T, n)
    first = np.where(hit.any(axis=0), times[hit.argmax(axis=0)], np.inf)
    stepped = np.isfinite(first)
    assert 0.2 * n < stepped.sum() < 0.8 * n  # both kinds of state are well represented
    # every overlap the steps see, the exact time saw first, and less than one step earlier
    assert np.isfinite(exact[stepped]).all()
    gap = first[stepped] - exact[stepped]
    assert (gap >= -1e-9).all() and (gap < DT_S + 1e-9).all()
    # where the steps see none within the horizon, contact is later, or a graze between steps
    missed = np.isfinite(exact) & ~stepped & (exact <= HORIZON_S - DT_S)
    assert missed.sum() <= 0.01 * n
    for i in np.flatnonzero(missed):
        assert box_gaps(ego[i:i + 1], other[i:i + 1] + v[i] * exact[i]) <= 1e-6


def test_first_contact_is_the_instant_the_boxes_touch() -> None:
    ego, other, v = _random_scene(1, 2000)
    t = first_contact_s(ego, other, v)
    later = np.isfinite(t) & (t > 0)
    at = other[later] + (v[later] * t[later, None])[:, None, :]
    assert np.abs(box_gaps(ego[later], at)).max() < 1e-6  # touching at t …
    before = other[later] + (v[later] * (t[later, None] - 1e-3))[:, None, :]
    assert (box_gaps(ego[later], before) > 0).all()  # … and apart just before


def test_known_answers() -> None:
    ego = _box(0.0, 0.0)
    # same lane, 20 m centre to centre, closing at 5 m/s: 20 − 4.8 = 15.2 m of gap, 3.04 s
    assert first_contact_s(ego, _box(20.0, 0.0), np.array([[-5.0, 0.0]])) == pytest.approx(3.04)
    # opening, or moving alongside in the next lane: never
    assert first_contact_s(ego, _box(20.0, 0.0), np.array([[5.0, 0.0]])) == np.inf
    assert first_contact_s(ego, _box(0.0, 3.7), np.array([[-5.0, 0.0]])) == np.inf
    # cut-in from the next lane: the lateral gap of 1.7 m closes at 1 m/s
    assert first_contact_s(ego, _box(0.0, 3.7), np.array([[0.0, -1.0]])) == pytest.approx(1.7)
    # crossing at right angles: the other's front (1 m from its centre… 2.4 m) meets y = 1
    crossing = first_contact_s(ego, _box(0.0, 13.4, np.pi / 2), np.array([[0.0, -10.0]]))
    assert crossing == pytest.approx((13.4 - 2.4 - 1.0) / 10.0)
    # already overlapping: 0, whatever the motion
    assert first_contact_s(ego, _box(1.0, 0.5), np.array([[3.0, 0.0]])) == 0.0


def test_broadcasts_over_leading_dimensions() -> None:
    ego = np.broadcast_to(_box(0.0, 0.0), (2, 3, 4, 2))
    others = box_corners(np.arange(6.0) * 10 + 10, np.zeros(6), np.zeros(6), np.full(6, 4.8),
                         np.full(6, 2.0)).reshape(2, 3, 4, 2)
    t = first_contact_s(ego, others, np.broadcast_to([-10.0, 0.0], (2, 3, 2)))
    assert t.shape == (2, 3)
    np.testing.assert_allclose(t.ravel(), (np.arange(6.0) * 10 + 10 - 4.8) / 10)


def test_gap_bound_never_exceeds_the_exact_gap_and_is_exact_for_aligned_boxes() -> None:
    s = _random_states(np.random.default_rng(3), 4000)
    zero, n = np.zeros(4000), 4000
    ego = (zero, zero, zero, np.full(n, 4.8), np.full(n, 2.0))
    other = (s["x"], s["y"], s["h"], s["length"], s["width"])
    exact = box_gaps(np.broadcast_to(_box(0.0, 0.0), (n, 4, 2)), box_corners(*other))
    bound = box_gap_bound(*ego, *other)
    assert (bound <= exact + 1e-9).all() and (bound == 0.0).any() and (bound > 0.0).any()
    aligned = box_gap_bound(*ego, s["x"], s["y"], zero, s["length"], s["width"])
    exact_aligned = box_gaps(np.broadcast_to(_box(0.0, 0.0), (n, 4, 2)),
                             box_corners(s["x"], s["y"], zero, s["length"], s["width"]))
    np.testing.assert_allclose(aligned, exact_aligned, atol=1e-9)
