"""Polyline geometry for the map: uniform resampling, a grid lookup and Frenet projection.

A `PolylineIndex` holds several polylines resampled to a uniform spacing and concatenated into
flat vertex arrays, with a sentinel vertex 0 (far away) standing for "no vertex". A grid over the
map stores, per cell, the nearest vertex within `reach_m` — optionally per heading sector, so that
where lanes cross a query finds the lane heading the query's way. A query is index arithmetic and
a tangent projection, with no per-point search: a handful of numpy calls whatever the map size,
which is what keeps the ADS inside its per-frame budget.

Every line also owns an interval of one *global arc coordinate* g (line l spans
[offset_l − EXTEND_M, offset_l + length_l + EXTEND_M], lines far apart), sampled with straight
extensions past both ends; a point at arc length s on line l is then one `np.interp` of
g = offset_l + s for all points of all lines at once, with straight extrapolation past the ends.
For the first line offset is 0, so g is simply its arc length.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence

import numpy as np

FAR_M = 1.0e9  # coordinate of the sentinel vertex
EXTEND_M = 300.0  # straight extension past both ends of every line, for extrapolation
_CACHE: dict[tuple, PolylineIndex] = {}
_CACHE_MAX = 16


def resample(points: np.ndarray, spacing_m: float) -> tuple[np.ndarray, float]:
    """The polyline (K, 2) resampled at uniform arc length ≤ spacing_m; returns (points, ds_m)."""
    seg = np.hypot(*np.diff(points, axis=0).T)
    keep = np.concatenate(([True], seg > 1e-9))
    points = points[keep]
    s = np.concatenate(([0.0], np.cumsum(seg[seg > 1e-9])))
    n = max(2, int(math.ceil(s[-1] / spacing_m)) + 1)
    s_new = np.linspace(0.0, s[-1], n)
    out = np.stack((np.interp(s_new, s, points[:, 0]), np.interp(s_new, s, points[:, 1])), axis=1)
    return out, float(s[-1] / (n - 1))


class PolylineIndex:
    """Resampled polylines with a nearest-vertex grid; build with `PolylineIndex.build`."""

    def __init__(
        self, polylines: Sequence[np.ndarray], spacing_m: float, reach_m: float, cell_m: float,
        sectors: int = 1,
    ) -> None:
        xs, ys, txs, tys, hs, gs, lines = [], [], [], [], [], [], []
        ig, ix, iy, ih = [], [], [], []  # interpolation samples in g, with the extensions
        offset = 0.0
        offsets, lengths = [], []
        for i, pts in enumerate(polylines):
            p, ds = resample(np.asarray(pts, dtype=float), spacing_m)
            t = np.gradient(p, axis=0)
            t /= np.hypot(t[:, 0], t[:, 1])[:, None]
            h = np.unwrap(np.arctan2(t[:, 1], t[:, 0]))
            s = np.arange(len(p)) * ds
            xs.append(p[:, 0])
            ys.append(p[:, 1])
            txs.append(t[:, 0])
            tys.append(t[:, 1])
            hs.append(h)
            gs.append(offset + s)
            lines.append(np.full(len(p), i))
            ig.append(np.concatenate(([-EXTEND_M], s, [s[-1] + EXTEND_M])) + offset)
            ix.append(np.concatenate(([p[0, 0] - EXTEND_M * t[0, 0]], p[:, 0],
                                      [p[-1, 0] + EXTEND_M * t[-1, 0]])))
            iy.append(np.concatenate(([p[0, 1] - EXTEND_M * t[0, 1]], p[:, 1],
                                      [p[-1, 1] + EXTEND_M * t[-1, 1]])))
            ih.append(np.concatenate(([h[0]], h, [h[-1]])))
            offsets.append(offset)
            lengths.append(s[-1])
            offset += s[-1] + 4.0 * EXTEND_M  # lines never share an interpolation interval

        def cat(parts: list[np.ndarray], pad: float) -> np.ndarray:
            return np.concatenate(([pad], *parts))

        self.x = cat(xs, FAR_M)  # (V + 1,) vertex 0 is the sentinel
        self.y = cat(ys, FAR_M)
        self.tx = cat(txs, 1.0)  # unit tangent
        self.ty = cat(tys, 0.0)
        self.heading = cat(hs, 0.0)  # tangent heading, unwrapped along each line
        self.g = cat(gs, 0.0)  # global arc coordinate of the vertex
        self.line = cat(lines, -1).astype(np.int64)
        self.offset = np.asarray(offsets)  # (L,) g of each line's start
        self.length_m = np.asarray(lengths)  # (L,)
        self._ig = np.concatenate(ig)  # (S,) strictly increasing
        self._ixy = np.concatenate(ix) + 1j * np.concatenate(iy)  # one interpolation for x and y
        self._ih = np.concatenate(ih)  # unwrapped heading
        if sectors & (sectors - 1):
            raise ValueError(f"sectors must be a power of two, got {sectors}")
        self._build_grid(reach_m, cell_m, sectors)

    @classmethod
    def build(
        cls, polylines: Sequence[np.ndarray], spacing_m: float, reach_m: float, cell_m: float,
        sectors: int = 1,
    ) -> PolylineIndex:
        """An index for these polylines, shared between instances built from identical input."""
        h = hashlib.blake2b(digest_size=16)
        for p in polylines:
            h.update(np.ascontiguousarray(p, dtype=float).tobytes())
            h.update(b"|")
        key = (h.digest(), spacing_m, reach_m, cell_m, sectors)
        index = _CACHE.get(key)
        if index is None:
            index = cls(polylines, spacing_m, reach_m, cell_m, sectors)
            if len(_CACHE) >= _CACHE_MAX:
                _CACHE.pop(next(iter(_CACHE)))
            _CACHE[key] = index
        return index

    def _build_grid(self, reach_m: float, cell_m: float, sectors: int) -> None:
        """Rasterise every vertex into the cells within reach; keep the nearest per cell (and
        heading sector: a vertex also serves the two neighbouring sectors)."""
        x, y = self.x[1:], self.y[1:]
        pad = reach_m + 2.0 * cell_m  # the border cells stay empty: off-grid points land there
        self.x0, self.y0 = float(x.min() - pad), float(y.min() - pad)
        self.nx = int(math.ceil((x.max() + pad - self.x0) / cell_m)) + 1
        self.ny = int(math.ceil((y.max() + pad - self.y0) / cell_m)) + 1
        self.inv_cell = 1.0 / cell_m
        r = int(math.ceil(reach_m / cell_m)) + 1
        oi, oj = (a.ravel() for a in np.meshgrid(np.arange(-r, r + 1), np.arange(-r, r + 1)))
        gi = np.floor((x - self.x0) / cell_m).astype(np.int64)[:, None] + oi  # (V, O)
        gj = np.floor((y - self.y0) / cell_m).astype(np.int64)[:, None] + oj
        dist = np.hypot(self.x0 + (gi + 0.5) * cell_m - x[:, None],
                        self.y0 + (gj + 0.5) * cell_m - y[:, None])
        keep = dist <= reach_m + 0.75 * cell_m  # a cell partly within reach is kept
        key = (gj * self.nx + gi)[keep]
        vert = np.broadcast_to(np.arange(1, len(x) + 1)[:, None], gi.shape)[keep]
        dist = dist[keep]
        self.sectors = sectors
        self._sector_scale = sectors / (2.0 * math.pi)
        self._sector_shift = 0.5 + 1024 * sectors  # keeps the value positive: truncation = floor
        if sectors > 1:
            sec = self.sector(self.heading[vert])
            key = np.concatenate([key * sectors + (sec + o) % sectors for o in (-1, 0, 1)])
            vert, dist = np.tile(vert, 3), np.tile(dist, 3)
        order = np.lexsort((dist, key))  # by key, nearest first
        key, vert = key[order], vert[order]
        first = np.ones(len(key), dtype=bool)
        first[1:] = key[1:] != key[:-1]
        table = np.zeros(self.nx * self.ny * sectors, dtype=np.int32)  # int32: half the cache
        table[key[first]] = vert[first]
        self.table = table
        self._nx_u = np.uint64(self.nx)
        self._i_max = np.uint64(self.nx - 1)
        self._j_max = np.uint64(self.ny - 1)

    def sector(self, heading_rad: np.ndarray) -> np.ndarray:
        """The heading sector (0 … sectors-1, centred on multiples of 2π/sectors) of headings."""
        return (heading_rad * self._sector_scale + self._sector_shift).astype(np.int64) & (
            self.sectors - 1
        )

    def candidates(
        self, px: np.ndarray, py: np.ndarray, heading_rad: np.ndarray | None = None
    ) -> np.ndarray:
        """The vertex nearest to each point (of a line heading like heading_rad, if the index
        has sectors); 0, the sentinel, where there is none within reach."""
        # a negative index viewed as unsigned is huge, so one minimum clamps both sides onto
        # the grid's border cells, which are empty by construction
        i = ((px - self.x0) * self.inv_cell).astype(np.int64).view(np.uint64)
        j = ((py - self.y0) * self.inv_cell).astype(np.int64).view(np.uint64)
        cell = np.minimum(j, self._j_max) * self._nx_u + np.minimum(i, self._i_max)
        if self.sectors > 1:
            cell = cell.view(np.int64) * self.sectors + self.sector(heading_rad)
        return self.table.take(cell)

    def project(
        self, px: np.ndarray, py: np.ndarray, v: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Project points (px, py) onto the tangents at vertices v (broadcastable).

        Returns (g, lateral_m, tx, ty): the global arc coordinate of the foot point, the signed
        distance to the left of the line, and the unit tangent there. With the grid's nearest
        vertex (≤ ~1 cell away) this is exact on straight lines and off by ≈ along²/(2·radius)
        (a few cm at a 10 m radius) on curves. For the sentinel (no vertex) |lateral_m| ≈ 1e9.
        """
        dx = px - self.x.take(v)
        dy = py - self.y.take(v)
        tx, ty = self.tx.take(v), self.ty.take(v)
        return self.g.take(v) + (dx * tx + dy * ty), tx * dy - ty * dx, tx, ty

    def project_point(self, x: float, y: float) -> tuple[float, float] | None:
        """(g, lateral_m) of one point, or None when no vertex is within reach (scalar path)."""
        i = math.floor((x - self.x0) * self.inv_cell)
        j = math.floor((y - self.y0) * self.inv_cell)
        if not (0 <= i < self.nx and 0 <= j < self.ny):
            return None
        v = int(self.table[(j * self.nx + i) * self.sectors])
        if v == 0:
            return None
        dx, dy = x - float(self.x[v]), y - float(self.y[v])
        tx, ty = float(self.tx[v]), float(self.ty[v])
        return float(self.g[v]) + dx * tx + dy * ty, tx * dy - ty * dx

    def nearest_vertex(self, x: float, y: float) -> int:
        """The nearest vertex by full search (slow path, for points off the grid)."""
        return int(np.argmin(np.hypot(self.x[1:] - x, self.y[1:] - y))) + 1

    def xy_at(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points at global arc coordinates g, straight beyond the line ends (contiguous arrays)."""
        xy = np.interp(g, self._ig, self._ixy)
        return xy.real.copy(), xy.imag.copy()

    def heading_at(self, g: np.ndarray) -> np.ndarray:
        """Tangent heading at g (unwrapped along each line)."""
        return np.interp(g, self._ig, self._ih)
