"""Polyline resampling, grid lookup and Frenet projection."""

import math

import numpy as np
from conftest import crossing_road, curved_road, polyline, straight_road

from evoeye.ads.geometry import PolylineIndex, resample


def test_resample_is_uniform_and_keeps_the_ends():
    pts = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.5]])
    out, ds = resample(pts, 1.0)
    steps = np.hypot(*np.diff(out, axis=0).T)
    assert ds <= 1.0
    assert (steps <= ds + 1e-9).all()
    assert np.isclose(steps, ds).sum() == len(steps) - 1  # only the step across the corner is short
    assert np.allclose(out[0], pts[0]) and np.allclose(out[-1], pts[-1])


def test_projection_on_a_straight_lane_is_exact():
    idx = PolylineIndex.build([lane.points for lane in straight_road().lanes], 1.0, 3.0, 1.0)
    px, py = np.array([10.3, 50.7]), np.array([0.8, 3.1])
    v = idx.candidates(px, py)
    g, lat, _, _ = idx.project(px, py, v)
    assert idx.line[v[0]] == 1 and idx.line[v[1]] == 0  # the nearest lanes: y = 0 and y = 4
    assert math.isclose(lat[0], 0.8, abs_tol=1e-9) and math.isclose(lat[1], -0.9, abs_tol=1e-9)
    # arc length along the lane that starts at x = −100
    assert math.isclose(g[0] - idx.offset[1], 110.3, abs_tol=1e-9)


def test_heading_sectors_pick_the_lane_going_the_queried_way():
    road = crossing_road()  # north along x = 0, east along y = 0, south along x = −4
    idx = PolylineIndex.build([lane.points for lane in road.lanes], 1.0, 3.0, 1.0, 8)
    px, py = np.full(4, 2.4), np.full(4, 0.4)  # near the crossing, nearer to the east lane
    v = idx.candidates(px, py, np.array([0.1, math.pi / 2 - 0.3, -7 * math.pi / 4, math.pi]))
    # east; north; 45° (as −315°): both serve it, east is nearer; west: no lane that way
    assert idx.line[v].tolist() == [1, 0, 1, -1]


def test_projection_on_a_curve_is_accurate():
    radius = 60.0
    idx = PolylineIndex.build([curved_road(radius).route.points], 1.0, 4.0, 1.0, 1)
    a = np.linspace(-1.2, 1.2, 7)
    r_pt = radius + np.array([-1.5, 0.0, 1.0, 2.0, -2.0, 0.5, 1.5])  # outside is to the right
    px, py = r_pt * np.cos(a), radius + r_pt * np.sin(a)
    g, lat, _, _ = idx.project(px, py, idx.candidates(px, py))
    assert np.allclose(lat, radius - r_pt, atol=0.02)
    assert np.allclose(g, radius * (a + math.pi / 2), atol=0.05)


def test_points_off_the_grid_get_the_sentinel():
    idx = PolylineIndex.build([polyline(0.0, 0.0, 0.0, 100.0)], 1.0, 3.0, 1.0, 1)
    px = np.array([50.0, 50.0, -500.0, 1e6, -1e6])
    py = np.array([0.0, 10.0, 0.0, 0.0, 0.0])
    v = idx.candidates(px, py)
    assert v[0] != 0 and (v[1:] == 0).all()
    _, lat, _, _ = idx.project(px, py, v)
    assert (np.abs(lat[1:]) > 1e6).all()  # never mistaken for a point near the line


def test_xy_at_follows_the_line_and_extrapolates_straight():
    idx = PolylineIndex.build([curved_road(30.0).route.points], 1.0, 3.0, 1.0, 1)
    g = np.array([0.0, 30.0 * math.pi / 2, 30.0 * math.pi + 20.0])
    x, y = idx.xy_at(g)
    assert np.allclose([x[0], y[0]], [0.0, 0.0], atol=1e-6)
    assert np.allclose([x[1], y[1]], [30.0, 30.0], atol=0.02)
    # past the end: straight on along the last chord (1 m chords on a 30 m radius)
    assert np.allclose([x[2], y[2]], [-20.0, 60.0], atol=0.5)
    assert x.flags.c_contiguous and y.flags.c_contiguous


def test_identical_input_shares_one_index():
    pts = [polyline(0.0, 0.0, 0.0, 50.0)]
    assert PolylineIndex.build(pts, 1.0, 3.0, 1.0) is PolylineIndex.build(
        [p.copy() for p in pts], 1.0, 3.0, 1.0
    )
