"""What the world looks like: the ground-truth scene at one instant and the static road map.

These are the only world types the ADS may see (perception reads `SceneState`; every module may
read the `RoadMap`, which stands for the HD map an ADS ships with). The simulator produces them;
`evoeye.ads` consumes them, so neither package imports the other's internals.
All positions are in the world frame, metres; headings in radians, counter-clockwise from +x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

EGO_ID = 0  # the ego is actor 0 and always the first row of a SceneState


@dataclass(slots=True)
class SceneState:
    """Ground truth of every present actor at time t_s (rows: actors, ego first)."""

    t_s: float
    actor_id: np.ndarray  # (N,) int64
    x_m: np.ndarray  # (N,)
    y_m: np.ndarray  # (N,)
    heading_rad: np.ndarray  # (N,)
    speed_mps: np.ndarray  # (N,) signed, along the heading
    accel_mps2: np.ndarray  # (N,) longitudinal
    length_m: np.ndarray  # (N,)
    width_m: np.ndarray  # (N,)
    crashed: np.ndarray  # (N,) bool
    ego_collision: bool  # the ego is in a collision at t_s
    collision_actor: int  # the actor the ego collided with first, -1 if none
    # static boxes that block the line of sight (buildings), (K, 4) [x_min, y_min, x_max, y_max]
    occluders: np.ndarray | None = None

    @property
    def n(self) -> int:
        return int(self.actor_id.shape[0])

    @property
    def vx_mps(self) -> np.ndarray:
        return self.speed_mps * np.cos(self.heading_rad)

    @property
    def vy_mps(self) -> np.ndarray:
        return self.speed_mps * np.sin(self.heading_rad)

    def relative_to_ego(self) -> EgoRelative:
        """Every other actor (rows 1…) in the ego's frame: x forward, y left."""
        h0 = float(self.heading_rad[0])
        c, s = np.cos(h0), np.sin(h0)
        ddx, ddy = self.x_m[1:] - self.x_m[0], self.y_m[1:] - self.y_m[0]
        dvx, dvy = self.vx_mps[1:] - self.vx_mps[0], self.vy_mps[1:] - self.vy_mps[0]
        return EgoRelative(c * ddx + s * ddy, -s * ddx + c * ddy, c * dvx + s * dvy,
                           -s * dvx + c * dvy,
                           (self.heading_rad[1:] - h0 + np.pi) % (2 * np.pi) - np.pi)


@dataclass(frozen=True)
class EgoRelative:
    """The other actors of a scene relative to the ego, in its frame (x forward, y left);
    (n − 1,) each, in the scene's row order."""

    dx_m: np.ndarray
    dy_m: np.ndarray
    dvx_mps: np.ndarray
    dvy_mps: np.ndarray
    dheading_rad: np.ndarray  # in [−π, π)


@dataclass(frozen=True)
class Lane:
    """A lane centre line as a dense polyline (K, 2) with cumulative arc length (K,)."""

    lane_id: str
    points: np.ndarray  # (K, 2) metres
    width_m: float
    speed_limit_mps: float
    # traffic on this lane must give way to traffic on the route where it ends (a minor road,
    # priority to the right): it is expected to stop at the lane's end unless the way is clear
    yields_to_route: bool = False

    @property
    def s_m(self) -> np.ndarray:
        seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        return np.concatenate(([0.0], np.cumsum(seg)))

    @property
    def heading_rad(self) -> np.ndarray:
        d = np.diff(self.points, axis=0)
        h = np.arctan2(d[:, 1], d[:, 0])
        return np.concatenate((h, h[-1:]))


@dataclass(frozen=True)
class RoadMap:
    """The static map: every drivable lane, and the ego's route as one lane-like polyline."""

    name: str
    lanes: tuple[Lane, ...]
    route: Lane  # the ego's intended path, concatenated over the lanes it traverses

    @classmethod
    def empty(cls, name: str) -> RoadMap:
        """A map with no lanes, for a run that failed before its world was built."""
        return cls(name=name, lanes=(), route=Lane("route", np.zeros((2, 2)), 0.0, 0.0))
