"""Hand-built ground truth for the audit's checks: actors as (t, x, y, heading, speed) paths."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evoeye.evaluation.audit.tracks import Tracks, tracks_from_messages

RATE_HZ = 20.0
LANE_WIDTH_M = 3.5


@dataclass
class ActorPath:
    """One actor's path on the frames where it is present (every array (T,))."""

    actor_id: int
    x_m: np.ndarray
    y_m: np.ndarray
    heading_rad: np.ndarray
    speed_mps: np.ndarray
    present: np.ndarray  # (T,) bool
    crashed: np.ndarray = field(default=None)  # (T,) bool

    @classmethod
    def from_velocity(cls, actor_id: int, x0_m: float, y0_m: float, vx_mps: np.ndarray,
                      vy_mps: np.ndarray, present: np.ndarray | None = None) -> ActorPath:
        """A path integrating a velocity profile from (x0, y0), heading along the velocity."""
        dt = 1.0 / RATE_HZ
        x = x0_m + np.concatenate(([0.0], np.cumsum(vx_mps[:-1]) * dt))
        y = y0_m + np.concatenate(([0.0], np.cumsum(vy_mps[:-1]) * dt))
        keep = np.ones(len(vx_mps), bool) if present is None else present
        return cls(actor_id, x, y, np.arctan2(vy_mps, vx_mps), np.hypot(vx_mps, vy_mps), keep)

    @classmethod
    def parked(cls, actor_id: int, n_frames: int, x_m: float, y_m: float) -> ActorPath:
        z = np.zeros(n_frames)
        return cls.from_velocity(actor_id, x_m, y_m, z + 1e-9, z)


def build_tracks(paths: list[ActorPath], ego_collision_frame: int | None = None) -> Tracks:
    """Tracks through the same decoder the logs go through (ground-truth message dicts)."""
    n_frames = len(paths[0].x_m)
    messages = []
    for i in range(n_frames):
        here = [p for p in paths if p.present[i]]
        crashed = [bool(p.crashed[i]) if p.crashed is not None else False for p in here]
        hit = ego_collision_frame is not None and i >= ego_collision_frame
        messages.append({
            "t_s": i / RATE_HZ,
            "actor_id": [p.actor_id for p in here],
            "x_m": [float(p.x_m[i]) for p in here],
            "y_m": [float(p.y_m[i]) for p in here],
            "heading_rad": [float(p.heading_rad[i]) for p in here],
            "vx_mps": [float(p.speed_mps[i] * np.cos(p.heading_rad[i])) for p in here],
            "vy_mps": [float(p.speed_mps[i] * np.sin(p.heading_rad[i])) for p in here],
            "length_m": [5.0] * len(here),
            "width_m": [2.0] * len(here),
            "crashed": crashed,
            "ego_collision": hit,
        })
    return tracks_from_messages(messages)


def straight_lanes(n_lanes: int = 2, length_m: float = 1000.0) -> tuple[np.ndarray, ...]:
    """Lanes along +x, LANE_WIDTH_M apart, from x = −100 m."""
    x = np.linspace(-100.0, length_m, 50)
    return tuple(np.stack([x, np.full_like(x, LANE_WIDTH_M * i)], axis=1) for i in range(n_lanes))


def lane_change_vy(a_lat_mps2: float, n_frames: int, start_frame: int = 20) -> np.ndarray:
    """(T,) lateral speed of a bang-bang lane change of LANE_WIDTH_M at ±a_lat_mps2."""
    half_s = np.sqrt(LANE_WIDTH_M / a_lat_mps2)  # each half covers half the width
    t = (np.arange(n_frames) - start_frame) / RATE_HZ
    return np.where(t < 0, 0.0, np.where(t < half_s, a_lat_mps2 * t,
                                         np.maximum(a_lat_mps2 * (2 * half_s - t), 0.0)))
