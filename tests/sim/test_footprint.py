"""Footprint gaps: the Euclidean distance between oriented vehicle rectangles."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evoeye.boxes import box_corners, box_gaps
from evoeye.scene import SceneState
from evoeye.sim.footprint import ego_gaps, min_ego_gap


def scene(*boxes: tuple[float, float, float]) -> SceneState:
    """Cars of 5 × 2 m at (x, y, heading); the first is the ego."""
    x, y, h = (np.array(v, float) for v in zip(*boxes, strict=True))
    n = len(boxes)
    return SceneState(0.0, np.arange(n), x, y, h, np.zeros(n), np.zeros(n), np.full(n, 5.0),
                      np.full(n, 2.0), np.zeros(n, bool), False, -1)


def test_known_gaps() -> None:
    gaps = ego_gaps(scene(
        (0, 0, 0),
        (0, 4, 0),  # side by side in the next lane: 4 m between centres, 2 m between sides
        (10, 0, 0),  # bumper to bumper, 5 m
        (0, 5, np.pi / 2),  # crossing ahead of the ego's flank: 5 − 2.5 − 1
        (7, 4, 0),  # corner to corner: (2.5, 1) → (4.5, 3)
        (1, 0.5, 0.3),  # overlapping
    ))
    np.testing.assert_allclose(gaps, [2.0, 5.0, 1.5, np.sqrt(8), 0.0], atol=1e-9)


def _dense_distance(a: np.ndarray, b: np.ndarray, k: int = 400) -> float:
    """Distance between two rectangles' outlines sampled densely (an upper bound, ≈ exact)."""
    def outline(c: np.ndarray) -> np.ndarray:
        t = np.linspace(0, 1, k, endpoint=False)[:, None]
        return np.concatenate([c[i] + t * (c[(i + 1) % 4] - c[i]) for i in range(4)])
    pa, pb = outline(a), outline(b)
    return float(np.sqrt(((pa[:, None] - pb[None]) ** 2).sum(-1)).min())


coord = st.floats(-12, 12)
angle = st.floats(-np.pi, np.pi)


@settings(max_examples=60, deadline=None)
@given(x=coord, y=coord, h0=angle, h1=angle)
def test_gap_matches_a_dense_outline_distance_when_apart(x, y, h0, h1) -> None:
    c = box_corners(np.array([0.0, x]), np.array([0.0, y]), np.array([h0, h1]),
                    np.array([5.0, 4.5]), np.array([2.0, 1.8]))
    gap = float(box_gaps(c[:1], c[1:])[0])
    dense = _dense_distance(c[0], c[1])
    if gap > 0:
        assert gap == pytest.approx(dense, abs=0.02)
        assert not _inside(c[1].mean(0), c[0]) and not _inside(c[0].mean(0), c[1])
    else:  # overlapping boxes: their outlines cross, or one holds the other
        assert dense < 0.02 or _inside(c[1].mean(0), c[0]) or _inside(c[0].mean(0), c[1])


def _inside(p: np.ndarray, box: np.ndarray) -> bool:
    """The point lies inside the (counter-clockwise) rectangle: left of every edge."""
    edges = np.roll(box, -1, axis=0) - box
    rel = p - box
    return bool((edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0] >= 0).all())


def test_min_ego_gap_is_the_smallest_exact_gap_over_the_run() -> None:
    run = [scene((0, 0, 0), (0, 4, 0), (40, 30, 1.0)), scene((0, 0, 0)),
           scene((0, 0, 0.1), (7, 4, 0), (6.5, 0, 0.2))]
    exact = min(float(ego_gaps(s).min()) for s in run if s.n > 1)
    assert exact < 2.0  # the third frame's car ahead, slightly turned, is nearest
    assert min_ego_gap(run) == exact
    assert min_ego_gap(run, batch=1) == exact  # however few exact distances a batch holds
    assert min_ego_gap([scene((0, 0, 0))]) == np.inf  # the ego alone


@settings(max_examples=60, deadline=None)
@given(x=coord, y=coord, h0=angle, h1=angle)
def test_min_ego_gap_matches_every_pair_computed_exactly(x, y, h0, h1) -> None:
    run = [scene((0, 0, h0), (x, y, h1), (x + 9, -y, h0)), scene((1, 1, h1), (-x, y, h0))]
    assert min_ego_gap(run, batch=1) == min(float(ego_gaps(s).min()) for s in run)
