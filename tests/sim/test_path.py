"""Paths: scalar lookups agree with numpy's interpolation value for value."""

import numpy as np
import pytest

from evoeye.sim.intersection import EGO_ROUTE, NPC_MOVES, _path, _route
from evoeye.sim.path import Path


def _interp_pose(path: Path, s_m: float) -> tuple[float, float, float]:
    return tuple(float(np.interp(s_m, path.s, v)) for v in (path.x, path.y, path.h))


@pytest.mark.parametrize("route", [tuple(EGO_ROUTE), tuple(_route(*NPC_MOVES["opp_left"]))])
def test_a_pose_is_numpys_interpolation_to_the_last_bit(route):
    path = _path(route)
    rng = np.random.default_rng(3)
    near = np.concatenate((path.s, np.nextafter(path.s, np.inf), np.nextafter(path.s, -np.inf)))
    for s in np.concatenate((rng.uniform(-5.0, path.length_m + 5.0, 2000), near[::7])).tolist():
        assert np.array(path.pose(s)).tobytes() == np.array(_interp_pose(path, s)).tobytes(), s


def test_a_pose_holds_the_ends_beyond_them_and_passes_nan_on():
    path = Path(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]))
    assert path.pose(-3.0) == _interp_pose(path, -3.0) == (0.0, 0.0, path.h[0])
    assert path.pose(path.length_m + 3.0) == _interp_pose(path, path.length_m + 3.0)
    assert path.pose(path.length_m) == (path.x[-1], path.y[-1], path.h[-1])
    assert all(np.isnan(v) for v in path.pose(float("nan")))


def _first_conflict_dense(a: Path, b: Path, radius_m: float) -> tuple[float, float] | None:
    """The definition, over all sample pairs at once."""
    near = (a.x[:, None] - b.x) ** 2 + (a.y[:, None] - b.y) ** 2 <= radius_m * radius_m
    rows = near.any(axis=1).nonzero()[0]
    if not len(rows):
        return None
    return float(a.s[rows[0]]), float(b.s[near[rows[0]].nonzero()[0][0]])


@pytest.mark.parametrize("radius_m", [0.05, 2.5, 4.5])
def test_the_first_conflict_is_the_first_sample_pair_within_the_radius(radius_m):
    moves = [tuple(EGO_ROUTE)] + [tuple(_route(*m)) for m in NPC_MOVES.values()]
    for a, b in ((a, b) for a in moves for b in moves if a != b):
        pa, pb = _path(a), _path(b)
        assert pa.first_conflict(pb, radius_m) == _first_conflict_dense(pa, pb, radius_m)
    apart = Path(np.array([[0.0, 0.0], [50.0, 0.0]])), Path(np.array([[0.0, 6.0], [50.0, 6.0]]))
    assert apart[0].first_conflict(apart[1], 4.5) is None
    assert apart[0].first_conflict(apart[1], 6.0) == (0.0, 0.0)  # exactly at the radius
