"""A driving path: highway-env lanes joined into one dense centre line with arc length.

NPCs move along a path in its Frenet frame (s along it, d to its left), so their kinematics are
exact and bounded by construction: the speed in a curve is limited by its curvature (preview
profile below), and a lane change is a smooth lateral offset profile. The path also answers the
geometric questions a scenario asks at set-up: how far along it a point lies, and where it first
comes close to another path (a conflict point).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from highway_env.road.lane import StraightLane
from scipy.spatial import cKDTree

SAMPLE_STEP_M = 0.5


class Path:
    """Centre line (K,) samples: x, y, continuous heading and curvature by arc length s."""

    def __init__(self, points: np.ndarray, step_m: float = SAMPLE_STEP_M) -> None:
        seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
        points = points[np.concatenate(([True], seg > 1e-6))]  # drop joints shared by lanes
        raw_s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))))
        n = max(2, int(math.ceil(raw_s[-1] / step_m)) + 1)
        self.s = np.linspace(0.0, raw_s[-1], n)  # (K,) uniform, so a lookup is an index
        self.step_m = float(self.s[1] - self.s[0])
        self.x = np.interp(self.s, raw_s, points[:, 0])
        self.y = np.interp(self.s, raw_s, points[:, 1])
        tx, ty = np.gradient(self.x), np.gradient(self.y)  # the tangent at each sample
        self.h = np.unwrap(np.arctan2(ty, tx))  # (K,) continuous heading
        kappa = np.gradient(self.h, self.s)
        if len(kappa) >= 5:
            kappa = np.convolve(kappa, np.ones(5) / 5.0, mode="same")
        self.kappa = kappa  # (K,) 1/m, smoothed
        self.length_m = float(self.s[-1])
        self._profiles: dict[tuple[float, float], np.ndarray] = {}
        self._dx, self._dy = self.x[1:] - self.x[:-1], self.y[1:] - self.y[:-1]  # (K-1,) segments
        self._seg2 = np.maximum(self._dx * self._dx + self._dy * self._dy, 1e-12)
        # the samples as floats, for scalar lookups (a numpy call per value costs more)
        self._samples = (self.s.tolist(), self.x.tolist(), self.y.tolist(), self.h.tolist())

    def index(self, s_m: float) -> int:
        """The sample at or before arc length s_m."""
        return min(max(int(s_m / self.step_m), 0), len(self.s) - 1)

    def turn(self, k0: int, k1: int) -> float:
        """|heading at sample k1 − heading at sample k0| (rad)."""
        h = self._samples[3]
        return abs(h[k1] - h[k0])

    @classmethod
    def from_lanes(cls, lanes: Sequence) -> Path:
        """The path through highway-env lanes `lanes`, in order."""
        parts = []
        for lane in lanes:
            if isinstance(lane, StraightLane):
                parts.append(np.stack([lane.start, lane.end]))
            else:
                n = max(2, int(math.ceil(lane.length / SAMPLE_STEP_M)) + 1)
                s = np.linspace(0.0, lane.length, n)
                parts.append(np.array([lane.position(si, 0.0) for si in s]))
        return cls(np.concatenate(parts))

    # -- lookups (scalars) ----------------------------------------------------------------------
    def _centre(self, s_m: float) -> tuple[float, float, float]:
        """(x, y, heading) on the centre line at s_m: `np.interp` of each, value for value (its
        arithmetic and end rules, in scalar Python, which a vehicle's every step can afford)."""
        s, x, y, h = self._samples
        if s_m != s_m:  # NaN
            return s_m, s_m, s_m
        if s_m <= s[0]:
            return x[0], y[0], h[0]
        if s_m >= s[-1]:
            return x[-1], y[-1], h[-1]
        j = min(int(s_m / self.step_m), len(s) - 2)  # s[j] ≤ s_m < s[j + 1], up to rounding
        while s[j] > s_m:
            j -= 1
        while s[j + 1] <= s_m:
            j += 1
        if s[j] == s_m:
            return x[j], y[j], h[j]
        ds, u = s[j + 1] - s[j], s_m - s[j]
        return ((x[j + 1] - x[j]) / ds * u + x[j], (y[j + 1] - y[j]) / ds * u + y[j],
                (h[j + 1] - h[j]) / ds * u + h[j])

    def pose(self, s_m: float, d_m: float = 0.0) -> tuple[float, float, float]:
        """(x, y, heading) of the point d_m to the left of the centre line at arc length s_m."""
        x, y, h = self._centre(s_m)
        if d_m:
            x -= d_m * math.sin(h)
            y += d_m * math.cos(h)
        return x, y, h

    def project(self, x: float, y: float, near_s: float | None = None,
                window_m: float = 10.0) -> tuple[float, float]:
        """(s, d) of the nearest point of the centre line: a full search, or one within
        window_m of `near_s` (for a vehicle followed from step to step)."""
        k0, k1 = 0, len(self.s) - 1
        if near_s is not None:
            k0 = self.index(near_s - window_m)
            k1 = min(self.index(near_s + window_m) + 1, len(self.s) - 1)
        px, py = self.x[k0:k1], self.y[k0:k1]
        dx, dy, seg2 = self._dx[k0:k1], self._dy[k0:k1], self._seg2[k0:k1]
        t = (((x - px) * dx + (y - py) * dy) / seg2).clip(0.0, 1.0)
        cx, cy = px + t * dx, py + t * dy
        k = int(np.argmin((cx - x) ** 2 + (cy - y) ** 2))
        s = float(self.s[k0 + k] + t[k] * math.sqrt(seg2[k]))
        h = math.atan2(dy[k], dx[k])
        return s, float(-(x - cx[k]) * math.sin(h) + (y - cy[k]) * math.cos(h))

    def speed_profile(self, lat_accel_mps2: float, decel_mps2: float) -> np.ndarray:
        """(K,) the highest speed at each sample from which every curve ahead can be taken within
        `lat_accel_mps2` by braking at most `decel_mps2` (v² = a_lat/|κ| in curves, then a
        backward pass: v_k ≤ sqrt(v_{k+1}² + 2·b·Δs)). Memoised: paths are shared by runs."""
        key = (lat_accel_mps2, decel_mps2)
        if key in self._profiles:
            return self._profiles[key]
        v = np.sqrt(lat_accel_mps2 / np.maximum(np.abs(self.kappa), 1e-6))
        ds = np.diff(self.s)
        for k in range(len(v) - 2, -1, -1):
            v[k] = min(v[k], math.sqrt(v[k + 1] ** 2 + 2.0 * decel_mps2 * ds[k]))
        self._profiles[key] = v
        return v

    def first_conflict(self, other: Path, radius_m: float) -> tuple[float, float] | None:
        """(s on this path, s on `other`) where this path first comes within radius_m of the
        other's centre line, or None if it never does. The samples are compared exactly as
        (dx² + dy² ≤ r²); a k-d tree only picks the samples that may qualify (within a hair
        more than r), so all K × K' pairs need not be formed."""
        pts = np.stack((self.x, self.y), axis=1)
        dist, _ = cKDTree(np.stack((other.x, other.y), axis=1)).query(
            pts, distance_upper_bound=radius_m * (1.0 + 1e-9) + 1e-9)
        r2 = radius_m * radius_m
        for k in np.isfinite(dist).nonzero()[0].tolist():  # in order along this path
            dx, dy = self.x[k] - other.x, self.y[k] - other.y
            near = (dx * dx + dy * dy) <= r2
            if np.count_nonzero(near):
                return float(self.s[k]), float(other.s[int(near.argmax())])
        return None

    def stop_before(self, other: Path, s_here: float, s_there: float, radius_m: float,
                    window_m: float = 20.0) -> float:
        """The last arc length before s_here (within window_m) from which this path keeps
        radius_m from the stretch of `other` around s_there: where to stop to let it pass.
        Stretches of `other` parallel to this path (an adjacent lane, either way) count only
        where they come closer than half a lane (a merge)."""
        k0, k1 = self.index(s_here - window_m), self.index(s_here)
        j0, j1 = other.index(s_there - window_m), other.index(s_there + window_m)
        dx = self.x[k0 : k1 + 1, None] - other.x[None, j0 : j1 + 1]
        dy = self.y[k0 : k1 + 1, None] - other.y[None, j0 : j1 + 1]
        d2 = dx * dx + dy * dy
        across = np.abs(np.sin(self.h[k0 : k1 + 1, None] - other.h[None, j0 : j1 + 1])) > 0.3
        near = ((d2 <= radius_m * radius_m) & across | (d2 <= 4.0)).any(axis=1)
        first = int(near.argmax()) if near.any() else len(near) - 1
        return float(self.s[k0 + max(first - 1, 0)])

