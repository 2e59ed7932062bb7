"""The lane an actor drives along: the nearest map lane whose heading matches its own.

Exact up to the lane resampling (0.5 m): one k-d tree per lane gives every point its nearest
vertex on every lane, and the nearest lane whose tangent there is within HEADING_MATCH_DEG of
the actor's heading wins. (A shared grid with heading sectors, as the ADS uses, answers from the
vertex nearest to a cell's centre and can pick a crossing lane inside an intersection.)
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
from scipy.spatial import cKDTree

from evoeye.ads.geometry import resample

LANE_SPACING_M = 0.5
LANE_REACH_M = 8.0  # farther than this from every matching lane: no lane (off the map)
HEADING_MATCH_DEG = 60.0
_CACHE: dict[bytes, LaneMatcher] = {}
_CACHE_MAX = 8


class LaneMatcher:
    """Nearest heading-matched lane tangents for batches of points; build with `for_lanes`."""

    def __init__(self, lanes: tuple[np.ndarray, ...]) -> None:
        self.trees: list[cKDTree] = []
        self.tangents: list[np.ndarray] = []  # (K, 2) unit tangents per lane
        for pts in lanes:
            p, _ = resample(np.asarray(pts, dtype=float), LANE_SPACING_M)
            t = np.gradient(p, axis=0)
            self.trees.append(cKDTree(p))
            self.tangents.append(t / np.hypot(t[:, 0], t[:, 1])[:, None])

    @classmethod
    def for_lanes(cls, lanes: tuple[np.ndarray, ...]) -> LaneMatcher:
        """A matcher for these lanes, shared by every run on the same map (per process)."""
        h = hashlib.blake2b(digest_size=16)
        for p in lanes:
            h.update(np.ascontiguousarray(p, dtype=float).tobytes() + b"|")
        key = h.digest()
        if key not in _CACHE:
            if len(_CACHE) >= _CACHE_MAX:
                _CACHE.pop(next(iter(_CACHE)))
            _CACHE[key] = cls(lanes)
        return _CACHE[key]

    def tangent(self, x_m: np.ndarray, y_m: np.ndarray, heading_rad: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """(tx, ty), each (N,): the unit tangent of the nearest lane heading within
        HEADING_MATCH_DEG of each point's heading; NaN where none is within LANE_REACH_M."""
        xy = np.column_stack([x_m, y_m])  # (N, 2)
        ux, uy = np.cos(heading_rad), np.sin(heading_rad)
        min_cos = math.cos(math.radians(HEADING_MATCH_DEG))
        best = np.full(len(xy), np.inf)
        tx, ty = np.full(len(xy), np.nan), np.full(len(xy), np.nan)
        for tree, tan in zip(self.trees, self.tangents, strict=True):
            dist, idx = tree.query(xy, distance_upper_bound=LANE_REACH_M)
            idx = np.minimum(idx, len(tan) - 1)  # "none within reach" is len(tan); dist is inf
            lx, ly = tan[idx, 0], tan[idx, 1]
            better = (dist < best) & (lx * ux + ly * uy >= min_cos)
            best = np.where(better, dist, best)
            tx, ty = np.where(better, lx, tx), np.where(better, ly, ty)
        return tx, ty
