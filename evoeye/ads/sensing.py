"""The sensor set: a 360° lidar and a long-range front radar, fused into one detection list.

Detections are made from the ground truth in the ego's sensor frame (x forward, y left) and
placed in the world with the ego pose *estimated* at capture time (ego-motion compensation), so
localisation errors move them as in a real stack. The lidar sees all around to `lidar_range_m`;
it misses more far away and behind nearer cars (angular shadowing), its noise grows with range,
and its boxes come from the visible points: a car seen end-on is a shorter box shifted towards the
sensor, and cars closer than `lidar_merge_gap_m` merge into one segment. The radar sees far ahead
in a narrow cone, with good range and range rate but poor azimuth, and no tangential velocity.
Where both see an actor, the radar's range and range rate correct the lidar's box along the line
of sight. False positives come from `evoeye.ads.clutter`. Each detection carries the variances of
its noise, as a real detector reports its uncertainty; the tracker uses them as its measurement
noise. Positions and velocities are complex numbers (x + iy) inside this module: a rotation is
one multiplication, which keeps a frame to a few dozen numpy calls.
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from evoeye.ads.clutter import FalsePositives
from evoeye.ads.config import SensorConfig
from evoeye.ads.detections import (
    DET_HEADING,
    DET_VX,
    DET_VY,
    DET_X,
    DET_Y,
    VAR_FLOOR,
    Detections,
    pack,
)
from evoeye.ads.messages import Localization
from evoeye.scene import SceneState

N_NORMALS = 8  # standard normals per actor and frame: lidar x, y, vx, vy, heading; radar r, az, rr


def line_of_sight_blocked(x0: float, y0: float, x: np.ndarray, y: np.ndarray,
                          boxes: np.ndarray | None) -> np.ndarray:
    """(n,) whether the segment from (x0, y0) to each (x, y) crosses a static box (K, 4)
    [x_min, y_min, x_max, y_max] (slab test, all pairs at once)."""
    if boxes is None or not len(boxes):
        return np.zeros(len(x), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_dx, inv_dy = 1.0 / (x - x0), 1.0 / (y - y0)  # (n,)
        tx1 = (boxes[None, :, 0] - x0) * inv_dx[:, None]  # (n, K)
        tx2 = (boxes[None, :, 2] - x0) * inv_dx[:, None]
        ty1 = (boxes[None, :, 1] - y0) * inv_dy[:, None]
        ty2 = (boxes[None, :, 3] - y0) * inv_dy[:, None]
    t_in = np.maximum(np.fmin(tx1, tx2), np.fmin(ty1, ty2))  # fmin/fmax: a NaN (0·inf) is
    t_out = np.minimum(np.fmax(tx1, tx2), np.fmax(ty1, ty2))  # an axis the segment runs along
    return ((t_out >= np.maximum(t_in, 0.0)) & (t_in <= 1.0)).any(axis=1)


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
    pos: np.ndarray, vel: np.ndarray, heading_rad: np.ndarray, length_m: np.ndarray,
    width_m: np.ndarray, range_m: np.ndarray, gap_m: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Lidar segmentation: merge detections whose true boxes are within gap_m of each other.

    pos, vel (m,) complex in the sensor frame; heading, length, width: the true boxes (m,). A
    detection with a nearer partner is absorbed by it: the partner's box grows to cover both (in
    the partner's orientation), its position moves to the merged box's centre and its velocity is
    averaged. Returns (kept mask, pos, vel, length, width) with the merged values.
    """
    rot = np.exp(-1j * heading_rad)  # (m,) into each detection's own frame
    rel = np.subtract.outer(pos, pos).T * rot[:, None]  # (m, m) j relative to i, in i's frame
    along, across = rel.real, rel.imag
    gap = np.maximum(np.abs(along) - 0.5 * np.add.outer(length_m, length_m),
                     np.abs(across) - 0.5 * np.add.outer(width_m, width_m))
    absorbs = (gap < gap_m) & np.less.outer(range_m, range_m)  # (m, m) i absorbs the farther j
    keep = ~absorbs.any(axis=0)
    group = absorbs & keep[:, None]  # only segments that are kept absorb
    if not np.count_nonzero(group):
        return keep, pos, vel, length_m, width_m
    group |= np.eye(len(pos), dtype=bool)
    hl, hw = 0.5 * length_m, 0.5 * width_m
    lo_a = np.where(group, along - hl, np.inf).min(axis=1)
    hi_a = np.where(group, along + hl, -np.inf).max(axis=1)
    lo_c = np.where(group, across - hw, np.inf).min(axis=1)
    hi_c = np.where(group, across + hw, -np.inf).max(axis=1)
    mid = 0.5 * ((lo_a + hi_a) + 1j * (lo_c + hi_c))
    return keep, pos + mid / rot, (group @ vel) / group.sum(axis=1), hi_a - lo_a, hi_c - lo_c


def to_world(z: np.ndarray, pose: tuple[float, float, float, float]) -> np.ndarray:
    """Sensor-frame detections (DET_FIELDS, m) → world frame, in place, for the ego pose
    (x, y, h, v); velocities are relative to the ego in the sensor frame."""
    x0, y0, h0, v0 = pose
    c, s = math.cos(h0), math.sin(h0)
    px, py = z[DET_X].copy(), z[DET_Y].copy()
    z[DET_X] = x0 + c * px - s * py
    z[DET_Y] = y0 + s * px + c * py
    vx, vy = z[DET_VX] + v0, z[DET_VY].copy()  # relative to the ego → absolute, ego-aligned
    z[DET_VX] = c * vx - s * vy
    z[DET_VY] = s * vx + c * vy
    z[DET_HEADING] += h0
    return z


class SensorModel:
    """Lidar + radar + false positives, fused into one detection list per frame."""

    def __init__(self, config: SensorConfig, rng: np.random.Generator) -> None:
        c = config
        self.c = c
        self.rng = rng
        self.false_positives = FalsePositives(c)
        # detection probabilities: near − drop·r², reaching the far value at the sensor's range
        self._lidar_drop = (c.lidar_detect_prob_near - c.lidar_detect_prob_far) / c.lidar_range_m**2
        self._radar_drop = (c.radar_detect_prob_near - c.radar_detect_prob_far) / c.radar_range_m**2
        self._inv_occ_lidar = 1.0 / c.occluded_fraction_max
        self._inv_occ_radar = 1.0 / c.radar_occluded_fraction_max
        self._radar_var_vel = c.radar_vel_sigma_mps**2 + VAR_FLOOR
        self._var_range = c.radar_range_sigma_m**2 + VAR_FLOOR  # radar variances, for the fusion
        self._var_range_rate = c.radar_range_rate_sigma_mps**2 + VAR_FLOOR

    def _may_merge(self, pos: np.ndarray, length_m: np.ndarray, width_m: np.ndarray) -> bool:
        """Whether any two lidar detections at pos (m,) complex may be close enough to merge:
        boxes within the gap have centres within hypot(L + gap, W + gap) of the largest car."""
        g = self.c.lidar_merge_gap_m
        reach = math.hypot(float(length_m.max()) + g, float(width_m.max()) + g)
        d = np.abs(np.subtract.outer(pos, pos))  # (m, m)
        return np.count_nonzero(d < reach) > len(pos)  # the diagonal is 0

    # The elementwise steps of `detect`, on arrays of n actors (n,) or of B runs' actors (B, n)
    # (`evoeye.ads.lockstep.sensing`): u, g are the frame's draws, (…, 3n + clutter) and
    # (…, N_NORMALS·n), sliced on their last axis.
    def seen_by(self, u: np.ndarray, n: int, r: np.ndarray, occ: np.ndarray,
                bearing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lidar, radar): which actors each sensor detects, from range, occlusion, bearing."""
        c = self.c
        r2 = r * r
        p_lidar = (c.lidar_detect_prob_near - self._lidar_drop * r2) * (
            1.0 - occ * self._inv_occ_lidar)
        p_radar = (c.radar_detect_prob_near - self._radar_drop * r2) * (
            1.0 - occ * self._inv_occ_radar)
        lidar = (u[..., :n] < p_lidar) & (r <= c.lidar_range_m)
        radar = (u[..., n:2 * n] < p_radar) & (r <= c.radar_range_m) & (
            np.abs(bearing) <= c.radar_half_fov_rad)
        return lidar, radar

    def lidar_boxes(self, g: np.ndarray, n: int, rel: np.ndarray, los: np.ndarray,
                    vrel: np.ndarray, h_rel: np.ndarray, r: np.ndarray, length: np.ndarray,
                    width: np.ndarray, cos_phi: np.ndarray, sin_phi: np.ndarray) -> tuple:
        """(pos, vel, heading, length, width, var_pos, var_vel) of the lidar boxes: made from
        the visible points (shorter end-on, centred on the visible part), with noise."""
        c = self.c
        gc = g[..., :4 * n].view(np.complex128)  # (…, 2n) position noise, velocity noise
        f = c.lidar_depth_seen_frac
        len_l = length * (f + (1.0 - f) * sin_phi)
        wid_l = width * (f + (1.0 - f) * cos_phi)
        shift = 0.5 * ((length - len_l) * cos_phi + (width - wid_l) * sin_phi)
        sig_p = c.pos_sigma_m + c.pos_sigma_per_m * r
        sig_v = c.vel_sigma_mps + c.vel_sigma_per_m * r
        pos_l = rel - shift * los + sig_p * gc[..., :n]
        vel_l = vrel + sig_v * gc[..., n:]
        head_l = h_rel + (c.heading_sigma_rad + c.heading_sigma_per_m * r) * g[..., 4 * n:5 * n]
        return (pos_l, vel_l, head_l, len_l, wid_l, sig_p * sig_p + VAR_FLOOR,
                sig_v * sig_v + VAR_FLOOR)

    def radar_fusion(self, g: np.ndarray, n: int, r: np.ndarray, bearing: np.ndarray,
                     vrel: np.ndarray, los: np.ndarray, both: np.ndarray, pos_l: np.ndarray,
                     vel_l: np.ndarray, var_pl: np.ndarray, var_vl: np.ndarray) -> tuple:
        """(range, line of sight, range rate) of the radar, and the lidar's position and
        velocity fused with it where `both` see the actor. The radar measures range and range
        rate only, so it corrects the lidar along its line of sight (a Kalman update with a
        radial measurement)."""
        c = self.c
        rm = r + c.radar_range_sigma_m * g[..., 5 * n:6 * n]
        los_r = np.exp(1j * (bearing + c.radar_azimuth_sigma_rad * g[..., 6 * n:7 * n]))
        rr = (vrel * los.conj()).real + c.radar_range_rate_sigma_mps * g[..., 7 * n:]
        if np.count_nonzero(both):
            back = los_r.conj()
            d_pos = (var_pl / (var_pl + self._var_range)) * (rm - (pos_l * back).real)
            d_vel = (var_vl / (var_vl + self._var_range_rate)) * (rr - (vel_l * back).real)
            pos_l = np.where(both, pos_l + d_pos * los_r, pos_l)
            vel_l = np.where(both, vel_l + d_vel * los_r, vel_l)
        return rm, los_r, rr, pos_l, vel_l

    def detect(self, scene: SceneState, ego: Localization | None = None) -> Detections:
        """Detections of every actor but the ego (row 0) at scene.t_s, in the world frame placed
        with `ego` (the localisation estimate at capture; None: the true pose)."""
        c = self.c
        n = len(scene.actor_id) - 1
        fp = self.false_positives
        # a fixed number of draws per frame, whatever is detected: the stream stays aligned
        u = self.rng.random(3 * n + fp.n_uniforms)
        g = self.rng.standard_normal(N_NORMALS * n)
        x, y, h, v = scene.x_m, scene.y_m, scene.heading_rad, scene.speed_mps
        x0, y0, h0, v0 = float(x[0]), float(y[0]), float(h[0]), float(v[0])
        pose = (x0, y0, h0, v0) if ego is None else (
            ego.x_m, ego.y_m, ego.heading_rad, ego.speed_mps)
        fp_ids, fp_z = fp.detect(u[3 * n:], v0)
        if n == 0:
            return Detections(fp_ids, to_world(fp_z, pose))
        # ground truth in the sensor frame (x forward, y left)
        rel = ((x[1:] - x0) + 1j * (y[1:] - y0)) * cmath.exp(-1j * h0)  # (n,)
        h_rel = h[1:] - h0
        e_h = np.exp(1j * h_rel)
        vrel = v[1:] * e_h - v0  # velocity relative to the ego
        r = np.abs(rel)
        bearing = np.arctan2(rel.imag, rel.real)  # (−π, π]: the seam is straight behind
        los = rel / r  # unit line of sight
        e_phi = e_h / los  # target orientation relative to the line of sight
        cos_phi, sin_phi = np.abs(e_phi.real), np.abs(e_phi.imag)
        length, width = scene.length_m[1:], scene.width_m[1:]
        occ = occluded_fraction(r, bearing, np.arctan2(length * sin_phi + width * cos_phi, r + r))
        if scene.occluders is not None:  # a building between: nothing to see
            occ = np.where(line_of_sight_blocked(x0, y0, x[1:], y[1:], scene.occluders), 1.0, occ)
        lidar, radar = self.seen_by(u, n, r, occ, bearing)
        pos_l, vel_l, head_l, len_l, wid_l, var_pl, var_vl = self.lidar_boxes(
            g, n, rel, los, vrel, h_rel, r, length, width, cos_phi, sin_phi)
        if np.count_nonzero(lidar) > 1 and self._may_merge(pos_l[lidar], length, width):
            i = lidar.nonzero()[0]
            keep, pos_l[i], vel_l[i], len_l[i], wid_l[i] = merge_segments(
                pos_l[i], vel_l[i], h_rel[i], length[i], width[i], r[i], c.lidar_merge_gap_m)
            lidar[i[~keep]] = False

        rm, los_r, rr, pos_l, vel_l = self.radar_fusion(
            g, n, r, bearing, vrel, los, lidar & radar, pos_l, vel_l, var_pl, var_vl)
        z = pack(pos_l, vel_l, head_l, len_l, wid_l, r, var_pl, var_vl)  # (DET_FIELDS, n)
        radar_only = radar & ~lidar
        if np.count_nonzero(radar_only):
            j = radar_only.nonzero()[0]
            pos_r, vel_r = rm[j] * los_r[j], rr[j] * los_r[j]
            vel_abs = vel_r + v0
            head_r = np.where(np.abs(vel_abs) > 1.0, np.arctan2(vel_abs.imag, vel_abs.real), 0.0)
            var_pr = np.maximum(self._var_range, (r[j] * c.radar_azimuth_sigma_rad) ** 2
                                + VAR_FLOOR)
            z[:, j] = pack(pos_r, vel_r, head_r, c.radar_length_m, c.radar_width_m, r[j], var_pr,
                           self._radar_var_vel)
        ids = scene.actor_id[1:]
        multipath = radar & (u[2 * n:3 * n] < c.ghost_prob) & (r > c.ghost_min_range_m)
        seen = lidar | radar
        if np.count_nonzero(seen) < n:
            ids, z, multipath = ids[seen], z[:, seen], multipath[seen]
        if np.count_nonzero(multipath):
            ghost_ids, ghosts = fp.ghosts(z[:, multipath])
            ids, z = np.concatenate((ids, ghost_ids)), np.concatenate((z, ghosts), axis=1)
        if len(fp_ids):
            ids, z = np.concatenate((ids, fp_ids)), np.concatenate((z, fp_z), axis=1)
        return Detections(ids, to_world(z, pose))
