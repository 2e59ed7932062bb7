"""The sensor set: a 360° lidar and a long-range front radar, fused into one detection list.

Detections are made from the ground truth in the ego's sensor frame (x forward, y left) and
placed in the world with the ego pose *estimated* at capture time (ego-motion compensation), so
localisation errors move them as in a real stack. The lidar sees all around to `lidar_range_m`;
it misses more far away and behind nearer cars (angular shadowing), its noise grows with range,
and its boxes come from the visible points: a car seen end-on is a shorter box shifted towards the
sensor, and cars closer than `lidar_merge_gap_m` merge into one segment. The radar sees far ahead
in a narrow cone, with good range and range rate but poor azimuth, and no tangential velocity.
Where both see an actor, the radar's range and range rate correct the lidar's box along the
line of sight. False positives
come from `evoeye.ads.clutter`. Each detection carries the variances of its noise, as a real
detector reports its uncertainty; the tracker uses them as its measurement noise.
Detections are columnar: one row per field (DET_*), one column per detection.
"""

from __future__ import annotations

import math

import numpy as np

from evoeye.ads.clutter import FalsePositives
from evoeye.ads.config import SensorConfig
from evoeye.ads.detections import (
    DET_FIELDS,
    DET_HEADING,
    DET_LENGTH,
    DET_RANGE,
    DET_VAR_POS,
    DET_VAR_VEL,
    DET_VX,
    DET_VY,
    DET_WIDTH,
    DET_X,
    DET_Y,
    VAR_FLOOR,
    Detections,
)
from evoeye.ads.messages import Localization
from evoeye.scene import SceneState

N_NORMALS = 8  # standard normals per actor and frame: lidar x, y, vx, vy, heading; radar r, az, rr


def occluded_fraction(
    range_m: np.ndarray, bearing_rad: np.ndarray, half_width_rad: np.ndarray
) -> np.ndarray:
    """Fraction of each target's angular extent covered by nearer actors, in [0, 1]. (n,)

    Pairwise: target i's interval [b_i − a_i, b_i + a_i] against every nearer j's interval;
    overlaps are summed (an upper bound on their union) and capped at 1. Bearings are not
    wrapped, so pass them relative to the sensor heading: the seam is then straight behind.
    """
    lo = bearing_rad - half_width_rad
    hi = bearing_rad + half_width_rad
    overlap = np.minimum.outer(hi, hi) - np.maximum.outer(lo, lo)  # (n, n) target i, actor j
    overlap = np.where(np.greater.outer(range_m, range_m), overlap, 0.0)  # nearer actors only
    return np.minimum(np.add.reduce(np.maximum(overlap, 0.0), axis=1) / (hi - lo), 1.0)


def merge_segments(
    z: np.ndarray, heading_rad: np.ndarray, length_m: np.ndarray, width_m: np.ndarray,
    gap_m: float,
) -> np.ndarray:
    """Lidar segmentation: merge detections whose true boxes are within gap_m; (m,) kept mask.

    z (DET_FIELDS, m) in the sensor frame, nearest first is not required. A detection with a
    nearer partner is absorbed by it: the partner's box grows to cover both (in the partner's
    orientation), its position moves to the merged box's centre and its velocity is averaged.
    """
    x, y = z[DET_X], z[DET_Y]
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    dx, dy = x[None, :] - x[:, None], y[None, :] - y[:, None]  # (m, m) j relative to i
    along = dx * c[:, None] + dy * s[:, None]  # in the frame of row i
    across = dy * c[:, None] - dx * s[:, None]
    gap = np.maximum(np.abs(along) - 0.5 * (length_m[:, None] + length_m),
                     np.abs(across) - 0.5 * (width_m[:, None] + width_m))
    r = z[DET_RANGE]
    absorbs = (gap < gap_m) & np.less.outer(r, r)  # (m, m) i absorbs the farther j
    keep = ~absorbs.any(axis=0)
    group = absorbs & keep[:, None]  # only segments that are kept absorb
    if not np.count_nonzero(group):
        return keep
    group |= np.eye(len(x), dtype=bool)
    hl, hw = 0.5 * length_m, 0.5 * width_m
    lo_a = np.where(group, along - hl, np.inf).min(axis=1)
    hi_a = np.where(group, along + hl, -np.inf).max(axis=1)
    lo_c = np.where(group, across - hw, np.inf).min(axis=1)
    hi_c = np.where(group, across + hw, -np.inf).max(axis=1)
    mid_a, mid_c = 0.5 * (lo_a + hi_a), 0.5 * (lo_c + hi_c)
    count = group.sum(axis=1)
    z[DET_X] = x + mid_a * c - mid_c * s
    z[DET_Y] = y + mid_a * s + mid_c * c
    z[DET_VX] = (group @ z[DET_VX]) / count
    z[DET_VY] = (group @ z[DET_VY]) / count
    z[DET_LENGTH] = hi_a - lo_a
    z[DET_WIDTH] = hi_c - lo_c
    return keep


def to_world(z: np.ndarray, pose: tuple[float, float, float, float]) -> np.ndarray:
    """Sensor-frame detections (DET_FIELDS, m) → world frame, for the ego pose (x, y, h, v)."""
    x0, y0, h0, v0 = pose
    c, s = math.cos(h0), math.sin(h0)
    out = z.copy()
    out[DET_X] = x0 + c * z[DET_X] - s * z[DET_Y]
    out[DET_Y] = y0 + s * z[DET_X] + c * z[DET_Y]
    vx, vy = z[DET_VX] + v0, z[DET_VY]  # relative to the ego → absolute, still ego-aligned
    out[DET_VX] = c * vx - s * vy
    out[DET_VY] = s * vx + c * vy
    out[DET_HEADING] = z[DET_HEADING] + h0
    return out


class SensorModel:
    """Lidar + radar + false positives, fused into one detection list per frame."""

    def __init__(self, config: SensorConfig, rng: np.random.Generator) -> None:
        c = config
        self.c = c
        self.rng = rng
        self.false_positives = FalsePositives(c)
        self._sigma_base = np.array([[c.pos_sigma_m], [c.pos_sigma_m], [c.vel_sigma_mps],
                                     [c.vel_sigma_mps], [c.heading_sigma_rad]])  # (5, 1)
        self._sigma_slope = np.array([[c.pos_sigma_per_m], [c.pos_sigma_per_m],
                                      [c.vel_sigma_per_m], [c.vel_sigma_per_m],
                                      [c.heading_sigma_per_m]])
        # detection probabilities: near − drop·r², reaching the far value at the sensor's range
        self._lidar_drop = (c.lidar_detect_prob_near - c.lidar_detect_prob_far) / c.lidar_range_m**2
        self._radar_drop = (c.radar_detect_prob_near - c.radar_detect_prob_far) / c.radar_range_m**2
        self._radar_var_vel = c.radar_vel_sigma_mps**2 + VAR_FLOOR

    def detect(self, scene: SceneState, ego: Localization | None = None) -> Detections:
        """Detections of every actor but the ego (row 0) at scene.t_s, in the world frame placed
        with `ego` (the localisation estimate at capture; None: the true pose)."""
        c = self.c
        n = len(scene.actor_id) - 1
        # a fixed number of draws per frame, whatever is detected: the stream stays aligned
        u = self.rng.random(3 * n + self.false_positives.n_uniforms)
        g = self.rng.standard_normal((N_NORMALS, n))
        x, y, h, v = scene.x_m, scene.y_m, scene.heading_rad, scene.speed_mps
        true_pose = (float(x[0]), float(y[0]), float(h[0]), float(v[0]))
        pose = true_pose if ego is None else (ego.x_m, ego.y_m, ego.heading_rad, ego.speed_mps)
        fp_ids, fp = self.false_positives.detect(u[3 * n:], true_pose[3])
        if n == 0:
            return self._finish(fp_ids, fp, pose)
        # ground truth in the sensor frame: a forward, b left; relative velocity
        c0, s0 = math.cos(true_pose[2]), math.sin(true_pose[2])
        dx, dy = x[1:] - true_pose[0], y[1:] - true_pose[1]
        a, b = c0 * dx + s0 * dy, c0 * dy - s0 * dx
        h_rel = h[1:] - true_pose[2]
        va, vb = v[1:] * np.cos(h_rel) - true_pose[3], v[1:] * np.sin(h_rel)
        r = np.hypot(a, b)  # (n,)
        bearing = np.arctan2(b, a)  # (−π, π]: the seam is straight behind
        ub, vbear = np.cos(bearing), np.sin(bearing)
        phi = h_rel - bearing  # target orientation relative to the line of sight
        cos_phi, sin_phi = np.abs(np.cos(phi)), np.abs(np.sin(phi))
        length, width = scene.length_m[1:], scene.width_m[1:]
        occ = occluded_fraction(r, bearing, np.arctan2(length * sin_phi + width * cos_phi, r + r))
        r2 = r * r
        p_lidar = (c.lidar_detect_prob_near - self._lidar_drop * r2) * (
            1.0 - occ * (1.0 / c.occluded_fraction_max))
        p_radar = (c.radar_detect_prob_near - self._radar_drop * r2) * (
            1.0 - occ * (1.0 / c.radar_occluded_fraction_max))
        lidar = (u[:n] < p_lidar) & (r <= c.lidar_range_m)
        radar = (u[n:2 * n] < p_radar) & (r <= c.radar_range_m) & (
            np.abs(bearing) <= c.radar_half_fov_rad)

        # lidar boxes from the visible points: shorter end-on, centred on the visible part
        f = c.lidar_depth_seen_frac
        seen_len = length * (f + (1.0 - f) * sin_phi)
        seen_wid = width * (f + (1.0 - f) * cos_phi)
        shift = 0.5 * ((length - seen_len) * cos_phi + (width - seen_wid) * sin_phi)
        sigma = self._sigma_base + self._sigma_slope * r  # (5, n)
        zl = np.empty((DET_FIELDS, n))
        zl[DET_X] = a - shift * ub + sigma[0] * g[0]
        zl[DET_Y] = b - shift * vbear + sigma[1] * g[1]
        zl[DET_VX] = va + sigma[2] * g[2]
        zl[DET_VY] = vb + sigma[3] * g[3]
        zl[DET_HEADING] = h_rel + sigma[4] * g[4]
        zl[DET_LENGTH] = seen_len
        zl[DET_WIDTH] = seen_wid
        zl[DET_RANGE] = r
        zl[DET_VAR_POS] = sigma[0] ** 2 + VAR_FLOOR
        zl[DET_VAR_VEL] = sigma[2] ** 2 + VAR_FLOOR
        if np.count_nonzero(lidar) > 1:
            idx = lidar.nonzero()[0]
            sub = zl[:, idx]
            keep = merge_segments(sub, h_rel[idx], length[idx], width[idx], c.lidar_merge_gap_m)
            zl[:, idx] = sub
            lidar[idx[~keep]] = False

        # radar: range and azimuth → position; range rate → the radial velocity only
        rm = r + c.radar_range_sigma_m * g[5]
        az = bearing + c.radar_azimuth_sigma_rad * g[6]
        ua, ul = np.cos(az), np.sin(az)
        rr = va * ub + vb * vbear + c.radar_range_rate_sigma_mps * g[7]
        zr = np.empty((DET_FIELDS, n))
        zr[DET_X], zr[DET_Y] = rm * ua, rm * ul
        zr[DET_VX], zr[DET_VY] = rr * ua, rr * ul
        moving = np.hypot(zr[DET_VX] + true_pose[3], zr[DET_VY]) > 1.0
        zr[DET_HEADING] = np.where(moving, np.arctan2(zr[DET_VY], zr[DET_VX] + true_pose[3]), 0.0)
        zr[DET_LENGTH], zr[DET_WIDTH] = c.radar_length_m, c.radar_width_m
        zr[DET_RANGE] = r
        zr[DET_VAR_POS] = np.maximum(c.radar_range_sigma_m**2, (r * c.radar_azimuth_sigma_rad) ** 2)
        zr[DET_VAR_POS] += VAR_FLOOR
        zr[DET_VAR_VEL] = self._radar_var_vel

        # fusion where both see the actor: the radar measures range and range rate only, so it
        # corrects the lidar along its line of sight (a Kalman update with a radial measurement)
        both = lidar & radar
        z = np.where(lidar, zl, zr)
        if np.count_nonzero(both):
            k_pos = zl[DET_VAR_POS] / (zl[DET_VAR_POS] + c.radar_range_sigma_m**2 + VAR_FLOOR)
            k_vel = zl[DET_VAR_VEL] / (zl[DET_VAR_VEL] + c.radar_range_rate_sigma_mps**2
                                       + VAR_FLOOR)
            d_pos = k_pos * (rm - (zl[DET_X] * ua + zl[DET_Y] * ul))
            d_vel = k_vel * (rr - (zl[DET_VX] * ua + zl[DET_VY] * ul))
            fused = zl[DET_X:DET_HEADING] + np.stack((d_pos * ua, d_pos * ul, d_vel * ua,
                                                      d_vel * ul))
            np.copyto(z[DET_X:DET_HEADING], fused, where=both)
        ghost_ids, ghosts = self.false_positives.ghosts(zr[:, radar], u[2 * n:3 * n][radar],
                                                        true_pose[3])
        seen = lidar | radar
        ids = np.concatenate((scene.actor_id[1:][seen], ghost_ids, fp_ids))
        return self._finish(ids, np.concatenate((z[:, seen], ghosts, fp), axis=1), pose)

    def _finish(self, ids: np.ndarray, z: np.ndarray, pose) -> Detections:
        return Detections(ids, to_world(z, pose))
