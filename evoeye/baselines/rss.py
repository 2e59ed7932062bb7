"""RSS baseline: safe longitudinal and lateral distances from the ad-rss library (Intel, v5).

Read from the last frame of each window. Each perceived obstacle is a structured constellation
in the ego's lane coordinates (x forward, y left; lanes `lane_width_m` wide): its longitudinal
speed is v_ego + dvx and its lateral speed dvy. Safe distances come from ad-rss's own
`ad_rss.rss.structured` functions with RssDynamics (CARLA's RSS defaults below):

* obstacle ahead moving forward: `calculateSafeLongitudinalDistanceSameDirection` (ego follows);
* obstacle ahead moving backward (oncoming): `…OppositeDirection`, the ego in its correct lane;
* obstacle behind moving forward: same direction, the obstacle follows; behind and moving
  away: no longitudinal constraint;
* lateral: `calculateSafeLateralDistance`, the obstacle left or right of the ego (ad-rss counts
  lateral speed positive to the right, so it gets −dvy; the ego's own lateral speed is 0).

Both road users get the same dynamics by default (response time 1 s); CARLA's RSS sensor gives
the other vehicles 2 s (`CARLA_OTHER_VEHICLES`, the `rss-2s` baseline).

Actual distances are bumper and side gaps; an obstacle within half a lane of the ego's centre
line is in the ego's lane and overlaps laterally (gap 0), as in a lane-based RSS world model.
Per axis the criticality is c = s / (s + d) for safe distance s and gap d (0.5 exactly at the
RSS boundary d = s, 1 at contact); an obstacle is as critical as its safer axis (RSS is violated
only when both are), and the risk is the max over obstacles. ad-rss is called once per distinct
pair of speeds rounded to `speed_grid_mps` (the distances depend on the speeds only) and the
answers are cached, so scoring stays vectorised; the distances are exactly ad-rss's for the
rounded speeds.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from evoeye.baselines.ttc import (
    DVX,
    DVY,
    DX,
    DY,
    EGO_LENGTH_M,
    EGO_WIDTH_M,
    LENGTH,
    WIDTH,
    rule_version,
)
from evoeye.store.features import CONTROL_FEATURES
from evoeye.store.windows import Windows

EGO_SPEED = CONTROL_FEATURES.index("ego_speed_mps")
LANE_WIDTH_M = 4.0


@dataclass(frozen=True)
class RssParams:
    """RSS dynamics of one road user (magnitudes; ad-rss takes braking as negative)."""

    response_time_s: float = 1.0
    accel_max_mps2: float = 3.5
    brake_max_mps2: float = 8.0
    brake_min_mps2: float = 4.0
    brake_min_correct_mps2: float = 3.0
    lat_accel_max_mps2: float = 0.2
    lat_brake_min_mps2: float = 0.8
    lateral_fluctuation_margin_m: float = 0.1
    max_speed_on_acceleration_mps: float = 100.0


CARLA_OTHER_VEHICLES = RssParams(response_time_s=2.0)  # CARLA's RssCheck: other vehicles 2 s


def _ad_rss():
    with warnings.catch_warnings():  # boost.python re-registers converters on import
        warnings.simplefilter("ignore", RuntimeWarning)
        import ad_rss
    return ad_rss


class AdRss:
    """The ad-rss safe-distance functions for fixed ego / other dynamics, on plain floats."""

    def __init__(self, ego: RssParams, other: RssParams) -> None:
        self.lib = _ad_rss()
        self._ego = self._state(ego)
        self._other = self._state(other)

    def _dynamics(self, p: RssParams):
        phys, world = self.lib.physics, self.lib.rss.world
        d = world.RssDynamics()
        d.alpha_lon.accel_max = phys.Acceleration(p.accel_max_mps2)
        d.alpha_lon.brake_max = phys.Acceleration(-p.brake_max_mps2)
        d.alpha_lon.brake_min = phys.Acceleration(-p.brake_min_mps2)
        d.alpha_lon.brake_min_correct = phys.Acceleration(-p.brake_min_correct_mps2)
        d.alpha_lat.accel_max = phys.Acceleration(p.lat_accel_max_mps2)
        d.alpha_lat.brake_min = phys.Acceleration(-p.lat_brake_min_mps2)
        d.lateral_fluctuation_margin = phys.Distance(p.lateral_fluctuation_margin_m)
        d.response_time = phys.Duration(p.response_time_s)
        d.max_speed_on_acceleration = phys.Speed(p.max_speed_on_acceleration_mps)
        d.min_longitudinal_safety_distance = phys.Distance(0.0)
        u = d.unstructured_settings  # unused by structured checks, but validated: ad-rss tests'
        u.pedestrian_turning_radius = phys.Distance(2.0)
        u.drive_away_max_angle = phys.Angle(2.4)
        u.vehicle_yaw_rate_change = phys.AngularAcceleration(0.3)
        u.vehicle_min_radius = phys.Distance(3.5)
        u.vehicle_trajectory_calculation_step = phys.Duration(0.2)
        return d

    def _state(self, p: RssParams):
        phys, rss = self.lib.physics, self.lib.rss
        s = rss.core.RelativeObjectState()
        s.object_type = rss.world.ObjectType.OtherVehicle
        s.dynamics = self._dynamics(p)
        st = s.structured_object_state
        st.is_in_correct_lane = True
        st.has_priority = False
        st.distance_to_enter_intersection = phys.Distance(0.0)
        st.distance_to_leave_intersection = phys.Distance(1000.0)
        u = s.unstructured_object_state
        u.yaw, u.steering_angle = phys.Angle(0.0), phys.Angle(0.0)
        u.yaw_rate = phys.AngularVelocity(0.0)
        u.dimension.length, u.dimension.width = phys.Distance(4.0), phys.Distance(2.0)
        u.center_point.x, u.center_point.y = phys.Distance(0.0), phys.Distance(0.0)
        u.speed_range.minimum, u.speed_range.maximum = phys.Speed(0.0), phys.Speed(0.0)
        return s

    def _set(self, state, lon_mps: float, lat_mps: float) -> object:
        phys = self.lib.physics
        v = state.structured_object_state.velocity
        v.speed_lon_min = v.speed_lon_max = phys.Speed(lon_mps)
        v.speed_lat_min = v.speed_lat_max = phys.Speed(lat_mps)
        return state

    def _call(self, fn, a, b) -> float:
        out = self.lib.physics.Distance(0.0)
        if not fn(a, b, out):
            raise ValueError(f"ad-rss {fn.__name__} rejected its input")
        return float(out.toBaseType)

    def lon_same_direction_m(self, follower_mps: float, leader_mps: float, ego_follows: bool):
        """Safe gap for a follower behind a leader, both moving forward."""
        s = self.lib.rss.structured.calculateSafeLongitudinalDistanceSameDirection
        ego, other = (follower_mps, leader_mps) if ego_follows else (leader_mps, follower_mps)
        e, o = self._set(self._ego, ego, 0.0), self._set(self._other, other, 0.0)
        return self._call(s, o, e) if ego_follows else self._call(s, e, o)

    def lon_opposite_direction_m(self, ego_mps: float, oncoming_mps: float) -> float:
        """Safe gap to an oncoming vehicle, the ego in its correct lane."""
        s = self.lib.rss.structured.calculateSafeLongitudinalDistanceOppositeDirection
        e = self._set(self._ego, ego_mps, 0.0)
        return self._call(s, e, self._set(self._other, oncoming_mps, 0.0))

    def lateral_m(self, other_lat_mps: float, other_is_left: bool) -> float:
        """Safe side gap; `other_lat_mps` in ad-rss's sign (positive = to the right)."""
        s = self.lib.rss.structured.calculateSafeLateralDistance
        e, o = self._set(self._ego, 0.0, 0.0), self._set(self._other, 0.0, other_lat_mps)
        return self._call(s, o, e) if other_is_left else self._call(s, e, o)


# Constellation kinds, and their safe distance as a function of two (rounded) speeds (a, b).
LON_EGO_FOLLOWS, LON_OTHER_FOLLOWS, LON_ONCOMING, LAT_OTHER_LEFT, LAT_OTHER_RIGHT, NONE = range(6)
SAFE_DISTANCE = {
    LON_EGO_FOLLOWS: lambda lib, a, b: lib.lon_same_direction_m(a, b, ego_follows=True),
    LON_OTHER_FOLLOWS: lambda lib, a, b: lib.lon_same_direction_m(a, b, ego_follows=False),
    LON_ONCOMING: lambda lib, a, b: lib.lon_opposite_direction_m(a, b),
    LAT_OTHER_LEFT: lambda lib, a, b: lib.lateral_m(b, other_is_left=True),
    LAT_OTHER_RIGHT: lambda lib, a, b: lib.lateral_m(b, other_is_left=False),
    NONE: lambda lib, a, b: 0.0,
}


@dataclass
class RSSMonitor:
    """Rule-based monitor: how far the newest frame's gaps fall below RSS safe distances."""

    ego: RssParams = field(default_factory=RssParams)
    other: RssParams = field(default_factory=RssParams)
    lane_width_m: float = LANE_WIDTH_M
    speed_grid_mps: float = 0.05
    ego_length_m: float = EGO_LENGTH_M
    ego_width_m: float = EGO_WIDTH_M
    name: str = "rss"  # "rss-2s" for the variant with CARLA_OTHER_VEHICLES
    context_len: int = 1
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _lib: AdRss | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def version(self) -> str:
        cfg = {f.name: getattr(self, f.name) for f in fields(self) if f.init}
        cfg["ego"], cfg["other"] = asdict(self.ego), asdict(self.other)
        return rule_version("rss", cfg)

    def _safe_m(self, kind: int, a_mps: float, b_mps: float) -> float:
        if self._lib is None:
            self._lib = AdRss(self.ego, self.other)
        return SAFE_DISTANCE[kind](self._lib, a_mps, b_mps)

    def safe_distances_m(self, kind: np.ndarray, a_mps: np.ndarray, b_mps: np.ndarray):
        """Safe distance (m) per item of constellation `kind` with speeds (a, b), via ad-rss."""
        q = self.speed_grid_mps
        keys = np.stack([kind, np.rint(a_mps / q), np.rint(b_mps / q)], axis=-1).astype(np.int64)
        uniq, inverse = np.unique(keys.reshape(-1, 3), axis=0, return_inverse=True)
        values = np.empty(len(uniq))
        for i, (k, a, b) in enumerate(uniq.tolist()):
            key = (k, a, b)
            if key not in self._cache:
                self._cache[key] = self._safe_m(k, a * q, b * q)
            values[i] = self._cache[key]
        return values[inverse.reshape(-1)].reshape(kind.shape)

    def criticality(self, perception: np.ndarray, mask: np.ndarray, ego_speed_mps: np.ndarray):
        """(B, n) RSS criticality in [0, 1] of each obstacle (0 on empty slots)."""
        dx, dy = perception[..., DX].astype(np.float64), perception[..., DY].astype(np.float64)
        v_ego = np.maximum(ego_speed_mps.astype(np.float64), 0.0)[:, None] + 0 * dx  # (B, n)
        v_lon = v_ego + perception[..., DVX]
        v_lat_right = -perception[..., DVY].astype(np.float64)  # ad-rss: positive = rightwards
        ahead = dx >= 0
        lon_kind = np.select(
            [~mask, ahead & (v_lon >= 0), ahead, v_lon >= 0],
            [NONE, LON_EGO_FOLLOWS, LON_ONCOMING, LON_OTHER_FOLLOWS], NONE,
        )
        used = lon_kind != NONE
        lon_a = np.where(lon_kind == LON_OTHER_FOLLOWS, v_lon, v_ego) * used  # follower / ego
        lon_b = np.where(lon_kind == LON_OTHER_FOLLOWS, v_ego, np.abs(v_lon)) * used
        lat_kind = np.select([~mask, dy >= 0], [NONE, LAT_OTHER_LEFT], LAT_OTHER_RIGHT)
        safe_lon = self.safe_distances_m(lon_kind, lon_a, lon_b)
        safe_lat = self.safe_distances_m(lat_kind, 0 * dx, v_lat_right * mask)
        gap_lon = np.maximum(np.abs(dx) - (self.ego_length_m + perception[..., LENGTH]) / 2, 0)
        gap_lat = np.maximum(np.abs(dy) - (self.ego_width_m + perception[..., WIDTH]) / 2, 0)
        gap_lat = np.where(np.abs(dy) < self.lane_width_m / 2, 0.0, gap_lat)  # same lane
        crit = np.minimum(_axis_criticality(safe_lon, gap_lon),
                          _axis_criticality(safe_lat, gap_lat))
        return np.where(mask, crit, 0.0)

    def score(self, windows: Windows) -> np.ndarray:
        rows = windows.context[:, -1]
        f = windows.features
        crit = self.criticality(f.perception[rows], f.perception_mask[rows],
                                f.control[rows, EGO_SPEED])
        return crit.max(axis=-1, initial=0.0)


def _axis_criticality(safe_m: np.ndarray, gap_m: np.ndarray) -> np.ndarray:
    """s / (s + d): 0 with no constraint, 0.5 at the RSS boundary, 1 at contact."""
    total = safe_m + gap_m
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(total > 0, safe_m / np.where(total > 0, total, 1.0), 1.0)
