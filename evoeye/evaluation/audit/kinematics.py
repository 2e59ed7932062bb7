"""Kinematic bounds on the NPCs before the ego's first collision: |a_lat|, |a_lon|, lateral speed.

Accelerations are the velocity vector differenced over `window_s` (3 frames at 20 Hz), split
along and across the mean heading of the window's two ends. Lateral speed is taken against the
road: the velocity component across the nearest map lane heading the actor's way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evoeye.evaluation.audit.lanes import LaneMatcher
from evoeye.evaluation.audit.tracks import Tracks


@dataclass(frozen=True)
class KinematicBounds:
    """The audit's bounds on NPC motion."""

    a_lat_mps2: float = 5.0
    a_lon_mps2: float = 9.5
    lat_speed_mps: float = 3.0
    window_s: float = 0.15


@dataclass(frozen=True)
class Peak:
    """The largest value of one quantity over a run's NPCs, who and when (for an acceleration,
    the end of its 0.15 s window); NO_PEAK when nothing was measured."""

    value: float
    actor_id: int
    t_s: float

    def to_dict(self) -> dict[str, float | int]:
        return {"value": self.value, "actor_id": self.actor_id, "t_s": self.t_s}


NO_PEAK = Peak(0.0, -1, float("nan"))


@dataclass(frozen=True)
class KinematicResult:
    """Per run: the peak |a_lat|, |a_lon| and lateral speed of any NPC, and the bounds broken."""

    a_lat: Peak
    a_lon: Peak
    lat_speed: Peak
    exceeded: tuple[str, ...]  # names among "a_lat", "a_lon", "lat_speed"

    @property
    def violated(self) -> bool:
        return bool(self.exceeded)


def _peak(values: np.ndarray, tracks: Tracks, t_s: np.ndarray) -> Peak:
    """The largest finite value of a (T', A) array, with its actor and time."""
    if not np.isfinite(values).any():
        return NO_PEAK
    i, j = np.unravel_index(np.nanargmax(values), values.shape)
    return Peak(float(values[i, j]), int(tracks.actor_id[j]), float(t_s[i]))


def accelerations(tracks: Tracks, lag: int) -> tuple[np.ndarray, np.ndarray]:
    """(a_lon, a_lat), each (T − lag, A) m/s²: velocity difference over `lag` frames, along and
    across the mean heading of its ends; NaN unless the actor is present at both ends."""
    dt = (tracks.t_s[lag:] - tracks.t_s[:-lag])[:, None]  # (T−lag, 1)
    ax = (tracks.vx_mps[lag:] - tracks.vx_mps[:-lag]) / dt
    ay = (tracks.vy_mps[lag:] - tracks.vy_mps[:-lag]) / dt
    h0, h1 = tracks.heading_rad[:-lag], tracks.heading_rad[lag:]
    ux, uy = np.cos(h0) + np.cos(h1), np.sin(h0) + np.sin(h1)  # mean direction, unnormalised
    norm = np.hypot(ux, uy)
    norm[norm < 1e-9] = np.nan  # a reversal within the window: no defined heading
    ux, uy = ux / norm, uy / norm
    return ax * ux + ay * uy, ux * ay - uy * ax


def road_lateral_speed(tracks: Tracks, lanes: tuple[np.ndarray, ...]) -> np.ndarray:
    """(T, A) |velocity across the nearest lane heading the actor's way|, m/s; NaN where the
    actor is absent or no such lane is near (see lanes.LaneMatcher)."""
    out = np.full(tracks.present.shape, np.nan)
    if not lanes:
        return out
    p = tracks.present
    tx, ty = LaneMatcher.for_lanes(lanes).tangent(tracks.x_m[p], tracks.y_m[p],
                                                  tracks.heading_rad[p])
    out[p] = np.abs(tracks.vy_mps[p] * tx - tracks.vx_mps[p] * ty)
    return out


def check_kinematics(tracks: Tracks, lanes: tuple[np.ndarray, ...], rate_hz: float,
                     bounds: KinematicBounds = KinematicBounds()) -> KinematicResult:
    """The NPCs' peak accelerations and road-lateral speed before the ego's first collision."""
    keep = np.zeros(tracks.present.shape[1], bool)
    keep[tracks.npc_columns()] = True
    before = tracks.before_ego_collision()[:, None] & keep[None, :]  # (T, A)
    lag = max(1, round(bounds.window_s * rate_hz))
    peaks = {"a_lat": NO_PEAK, "a_lon": NO_PEAK}
    if len(tracks.t_s) > lag:
        a_lon, a_lat = accelerations(tracks, lag)
        window = before[lag:] & before[:-lag]  # (T−lag, A) both ends before the collision
        t_end = tracks.t_s[lag:]
        peaks = {"a_lat": _peak(np.where(window, np.abs(a_lat), np.nan), tracks, t_end),
                 "a_lon": _peak(np.where(window, np.abs(a_lon), np.nan), tracks, t_end)}
    lat = np.where(before, road_lateral_speed(tracks, lanes), np.nan)
    peaks["lat_speed"] = _peak(lat, tracks, tracks.t_s)
    limits = {"a_lat": bounds.a_lat_mps2, "a_lon": bounds.a_lon_mps2,
              "lat_speed": bounds.lat_speed_mps}
    exceeded = tuple(name for name, peak in peaks.items() if peak.value > limits[name])
    return KinematicResult(**peaks, exceeded=exceeded)
