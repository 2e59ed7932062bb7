"""Small maps, scenes and a kinematic-bicycle world for the ADS tests (no highway-env)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pytest

from evoeye.ads import ADSConfig
from evoeye.ads.config import SensorConfig
from evoeye.ads.messages import Localization, Obstacles, Predictions
from evoeye.scene import Lane, RoadMap, SceneState

DT_S = 0.05
LANE_W_M = 4.0


def polyline(x0: float, y0: float, heading_rad: float, length_m: float, step_m: float = 1.0):
    """A straight polyline (K, 2)."""
    s = np.arange(0.0, length_m + 1e-9, step_m)
    return np.stack((x0 + s * math.cos(heading_rad), y0 + s * math.sin(heading_rad)), axis=1)


def lane(lane_id: str, points: np.ndarray) -> Lane:
    return Lane(lane_id=lane_id, points=points, width_m=LANE_W_M, speed_limit_mps=30.0)


def straight_road() -> RoadMap:
    """Three lanes along +x (y = −4, 0, +4), 800 m; the route is the middle lane."""
    lanes = tuple(lane(f"l{i}", polyline(-100.0, y, 0.0, 800.0)) for i, y in enumerate((4, 0, -4)))
    return RoadMap(name="straight", lanes=lanes, route=lanes[1])


def crossing_road() -> RoadMap:
    """The route goes north along x = 0; a crossing lane goes east along y = 0; an oncoming lane
    goes south along x = −4."""
    north = lane("north", polyline(0.0, -200.0, math.pi / 2, 400.0))
    east = lane("east", polyline(-200.0, 0.0, 0.0, 400.0))
    south = lane("south", polyline(-4.0, 200.0, -math.pi / 2, 400.0))
    return RoadMap(name="crossing", lanes=(north, east, south), route=north)


def curved_road(radius_m: float = 60.0) -> RoadMap:
    """One lane: a circle arc of the given radius, counter-clockwise, 180° long."""
    a = np.linspace(-math.pi / 2, math.pi / 2, int(math.pi * radius_m))
    pts = np.stack((radius_m * np.cos(a), radius_m + radius_m * np.sin(a)), axis=1)
    ln = lane("arc", pts)
    return RoadMap(name="curve", lanes=(ln,), route=ln)


def make_scene(t_s: float, actors: list[tuple[float, float, float, float]]) -> SceneState:
    """A scene from rows (x, y, heading, speed); row 0 is the ego. Cars are 5 m × 2 m."""
    a = np.asarray(actors, dtype=float).reshape(-1, 4)
    n = len(a)
    return SceneState(
        t_s=t_s, actor_id=np.arange(n, dtype=np.int64), x_m=a[:, 0].copy(), y_m=a[:, 1].copy(),
        heading_rad=a[:, 2].copy(), speed_mps=a[:, 3].copy(), accel_mps2=np.zeros(n),
        length_m=np.full(n, 5.0), width_m=np.full(n, 2.0), crashed=np.zeros(n, dtype=bool),
        ego_collision=False, collision_actor=-1,
    )


@dataclass
class BicycleWorld:
    """The ego as highway-env's kinematic bicycle; NPCs move at constant velocity."""

    ego: list[float]  # x, y, heading, speed
    npcs: list[list[float]] = field(default_factory=list)  # rows x, y, heading, speed
    t_s: float = 0.0
    length_m: float = 5.0

    def scene(self) -> SceneState:
        return make_scene(self.t_s, [self.ego, *self.npcs])

    def step(self, accel_mps2: float, steering_rad: float, dt: float = DT_S) -> None:
        x, y, h, v = self.ego
        beta = math.atan(0.5 * math.tan(steering_rad))
        x += v * math.cos(h + beta) * dt
        y += v * math.sin(h + beta) * dt
        h += v * math.sin(beta) / (self.length_m / 2) * dt
        v += accel_mps2 * dt
        self.ego = [x, y, h, v]
        for npc in self.npcs:
            npc[0] += npc[3] * math.cos(npc[2]) * dt
            npc[1] += npc[3] * math.sin(npc[2]) * dt
        self.t_s += dt

    def gap_m(self) -> float:
        """Smallest centre distance from the ego to an NPC."""
        if not self.npcs:
            return math.inf
        return min(math.hypot(n[0] - self.ego[0], n[1] - self.ego[1]) for n in self.npcs)

    def overlaps(self) -> bool:
        """Whether the ego's 5 m × 2 m box overlaps any NPC's (separating axis test)."""
        return any(_boxes_overlap(self.ego, n) for n in self.npcs)


def _corners(x: float, y: float, h: float) -> np.ndarray:
    c, s = math.cos(h), math.sin(h)
    local = np.array([[2.5, 1.0], [2.5, -1.0], [-2.5, -1.0], [-2.5, 1.0]])
    return np.stack((x + local[:, 0] * c - local[:, 1] * s, y + local[:, 0] * s + local[:, 1] * c),
                    axis=1)


def _boxes_overlap(a, b) -> bool:
    pa, pb = _corners(*a[:3]), _corners(*b[:3])
    for h in (a[2], b[2]):
        for axis in (np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])):
            qa, qb = pa @ axis, pb @ axis
            if qa.max() < qb.min() or qb.max() < qa.min():
                return False
    return True


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(7)


def ideal_sensor(**changes) -> SensorConfig:
    """A sensor set without noise, misses, false positives or latency, seeing whole boxes
    (occlusion, range limits, segment merging and the radar's missing tangential velocity
    still apply)."""
    base = dict(
        lidar_detect_prob_near=1.0, lidar_detect_prob_far=1.0, radar_detect_prob_near=1.0,
        radar_detect_prob_far=1.0, pos_sigma_m=0.0, pos_sigma_per_m=0.0, vel_sigma_mps=0.0,
        vel_sigma_per_m=0.0, heading_sigma_rad=0.0, heading_sigma_per_m=0.0,
        radar_range_sigma_m=0.0, radar_azimuth_sigma_rad=0.0, radar_range_rate_sigma_mps=0.0,
        lidar_depth_seen_frac=1.0, clutter_rate_per_frame=0.0, ghost_prob=0.0, latency_s=0.0,
    )
    base.update(changes)
    return replace(ADSConfig.cautious().sensor, **base)


def ego_at(x: float, y: float, heading: float = 0.0, speed: float = 0.0, t_s: float = 0.0):
    return Localization(t_s=t_s, x_m=x, y_m=y, heading_rad=heading, speed_mps=speed,
                        accel_mps2=0.0)


def obstacles(rows: list[tuple[float, float, float, float]], t_s: float = 0.0) -> Obstacles:
    """Tracked obstacles from rows (x, y, heading, speed); ids 1…n, 5 m × 2 m cars."""
    a = np.asarray(rows, dtype=float).reshape(-1, 4)
    n = len(a)
    return Obstacles(
        t_s=t_s, track_id=np.arange(1, n + 1), obj_class=["car"] * n, x_m=a[:, 0], y_m=a[:, 1],
        heading_rad=a[:, 2], vx_mps=a[:, 3] * np.cos(a[:, 2]), vy_mps=a[:, 3] * np.sin(a[:, 2]),
        length_m=np.full(n, 5.0), width_m=np.full(n, 2.0), confidence=np.ones(n),
    )


def cv_predictions(rows: list[tuple[float, float, float, float]], t_s: float = 0.0,
                   horizon_s: float = 3.0, dt_s: float = 0.1) -> Predictions:
    """Constant-velocity predictions from rows (x, y, heading, speed); ids 1…n."""
    a = np.asarray(rows, dtype=float).reshape(-1, 4)
    n = len(a)
    t = (np.arange(round(horizon_s / dt_s)) + 1.0) * dt_s
    vx, vy = a[:, 3] * np.cos(a[:, 2]), a[:, 3] * np.sin(a[:, 2])
    return Predictions(
        t_s=t_s, dt_s=dt_s, track_id=np.arange(1, n + 1), model=["cv"] * n, mode_prob=np.ones(n),
        length_m=np.full(n, 5.0), width_m=np.full(n, 2.0),
        x_m=a[:, :1] + vx[:, None] * t, y_m=a[:, 1:2] + vy[:, None] * t,
    )
