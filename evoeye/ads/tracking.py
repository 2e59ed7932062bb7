"""Multi-object tracking: a batched constant-velocity Kalman filter with stable track ids.

Why not one `filterpy.kalman.KalmanFilter` per track: measured on this machine (numpy 2.4,
Python 3.11), one filterpy predict+update with 4 states and 4 measurements costs 18.3 µs per
track, 111 µs for 6 tracks — almost half of the whole ADS's 0.25 ms frame budget, before any
association. This filter uses that a CV model with isotropic process and measurement noise makes
the x and y axes independent with identical covariance, so a track needs one symmetric 2×2
covariance [pos, vel] (three numbers) for both axes, and all tracks are filtered at once in closed
form: `CVTracker.step` for 6 tracks — predict, gate, linear_sum_assignment, update, prune — takes
33 µs, the update alone 15 µs, nearly independent of the number of tracks.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from evoeye.ads.config import TrackerConfig
from evoeye.ads.detections import (
    DET_HEADING,
    DET_RANGE,
    DET_VAR_POS,
    DET_VAR_VEL,
    DET_X,
    DET_Y,
)

# rows of the (TRACK_FIELDS, m) track state: kinematics, per-axis covariance, the rest
X, Y, VX, VY, P_PP, P_PV, P_VV, HEADING, LENGTH, WIDTH, RANGE, HITS, MISSES = range(13)
TRACK_FIELDS = 13
UNASSIGNABLE = 1.0e6


class CVTracker:
    """All tracks in one columnar array `state` (TRACK_FIELDS, m) plus `track_id` (m,)."""

    def __init__(self, config: TrackerConfig, dt_s: float) -> None:
        self.c = config
        self.dt_s = dt_s
        self.state = np.zeros((TRACK_FIELDS, 0))
        self.track_id = np.zeros(0, dtype=np.int64)
        self.confirmed = np.zeros(0, dtype=bool)  # (m,) published: at least confirm_hits hits
        self._next_id = 1
        s2 = config.accel_noise_mps2**2
        # the per-axis covariance [pp, pv, vv] propagates linearly: new = A @ old + q
        self._cov_a = np.array([[1.0, 2.0 * dt_s, dt_s * dt_s], [0.0, 1.0, dt_s], [0.0, 0.0, 1.0]])
        self._cov_q = np.array([[s2 * dt_s**4 / 4.0], [s2 * dt_s**3 / 2.0], [s2 * dt_s**2]])
        self._miss_limit = np.array([config.tentative_max_misses, config.max_coast_frames])

    def step(self, z: np.ndarray) -> None:
        """Predict every track by one frame; associate and update with detections z (10, k)."""
        st = self.state
        st[X:VX] += st[VX:P_PP] * self.dt_s
        st[P_PP:HEADING] = self._cov_a @ st[P_PP:HEADING] + self._cov_q
        st[MISSES] += 1.0  # reset below for the tracks that get a detection
        m, k = st.shape[1], z.shape[1]
        if m and k:
            gate = self.c.gate_m
            cost = np.hypot(st[X][:, None] - z[DET_X], st[Y][:, None] - z[DET_Y])  # (m, k)
            rows, cols = linear_sum_assignment(np.where(cost <= gate, cost, UNASSIGNABLE))
            ok = cost[rows, cols] <= gate
            if np.count_nonzero(ok) < len(ok):
                rows, cols = rows[ok], cols[ok]
            if len(rows):
                self._update(rows if len(rows) < m else None, z[:, cols])
            if len(cols) < k:
                fresh = np.ones(k, dtype=bool)
                fresh[cols] = False
                self._spawn(z[:, fresh])
        elif k:
            self._spawn(z)
        self._prune()

    def _update(self, rows: np.ndarray | None, z: np.ndarray) -> None:
        """Update the tracks `rows` (None: all) with detections z (10, r) (`update_tracks`)."""
        s = self.state if rows is None else self.state[:, rows]  # (13, r)
        update_tracks(s, z)
        if rows is not None:
            self.state[:, rows] = s

    def _spawn(self, z: np.ndarray) -> None:
        """A tentative track per unassociated detection."""
        n = z.shape[1]
        self.state = np.concatenate((self.state, new_tracks(z)), axis=1)
        self.track_id = np.concatenate((self.track_id, np.arange(self._next_id, self._next_id + n)))
        self._next_id += n

    def _prune(self) -> None:
        """Drop tentative tracks that missed too often and confirmed ones coasted too long."""
        confirmed = self.state[HITS] >= self.c.confirm_hits
        misses = self.state[MISSES]
        if misses.size and np.maximum.reduce(misses) > self.c.tentative_max_misses:
            alive = misses <= self._miss_limit.take(confirmed.view(np.int8))
            if np.count_nonzero(alive) < len(alive):
                self.state = self.state[:, alive]
                self.track_id = self.track_id[alive]
                confirmed = confirmed[alive]
        self.confirmed = confirmed

    def confidence(self, s: np.ndarray, range_m: float) -> np.ndarray:
        """Confidence in [0, 1] of tracks with states s (13, n), from hits, range and misses."""
        c = self.c
        hits = s[HITS]
        return (hits / (hits + c.confidence_hits_scale)) * (
            (1.0 - (c.confidence_range_drop / range_m) * s[RANGE])  # detection range ≤ range_m
            * c.confidence_coast_decay ** s[MISSES]
        )


def update_tracks(s: np.ndarray, z: np.ndarray) -> None:
    """Closed-form Kalman update, in place, of the tracks with states s (13, r) with their
    detections z (10, r) (the lockstep engine updates the tracks of many runs in one call).

    Per axis, with P = [[pp, pv], [pv, vv]], S = P + R, R = diag(rp, rv): K = P S⁻¹, and since
    the whole state is measured, the posterior covariance P − K P equals K R.
    """
    pp, pv, vv = s[P_PP], s[P_PV], s[P_VV]
    rp, rv = z[DET_VAR_POS], z[DET_VAR_VEL]
    s00 = pp + rp
    s11 = vv + rv
    pv2 = pv * pv
    inv_det = 1.0 / (s00 * s11 - pv2)
    k00 = (pp * s11 - pv2) * inv_det
    k11 = (vv * s00 - pv2) * inv_det
    q = pv * inv_det  # K[0, 1] = q·rp, K[1, 0] = q·rv
    e = z[DET_X:DET_HEADING] - s[X:P_PP]  # (4, r) innovations x, y, vx, vy
    k01 = q * rp
    s[X:P_PP] += np.concatenate((k00 * e[:2] + k01 * e[2:], (q * rv) * e[:2] + k11 * e[2:]))
    s[P_PV] = k01 * rv
    s[P_PP] = k00 * rp
    s[P_VV] = k11 * rv
    s[HEADING:HITS] = z[DET_HEADING:DET_RANGE + 1]  # box orientation and size as detected
    s[HITS] += 1.0
    s[MISSES] = 0.0


def new_tracks(z: np.ndarray) -> np.ndarray:
    """The states (13, n) of new tentative tracks, one per detection of z (10, n)."""
    s = np.zeros((TRACK_FIELDS, z.shape[1]))
    s[X:P_PP] = z[DET_X:DET_HEADING]
    s[P_PP] = z[DET_VAR_POS]
    s[P_VV] = z[DET_VAR_VEL]
    s[HEADING:HITS] = z[DET_HEADING:DET_RANGE + 1]
    s[HITS] = 1.0
    return s
