"""Which topics carry what, and the vehicle the conventions need: defaults, or a small TOML file.

A mapping file overrides any subset of the defaults:

    [topics]
    odometry = "/localization/kinematic_state"
    ground_truth_objects = "/awsim/ground_truth/objects"
    collision = ""                       # "" switches a topic off

    [planning_factors]                   # factor topic → the evoeye decision it means
    "/planning/planning_factors/obstacle_stop" = "yield"

    [vehicle]
    length_m = 4.9
    rear_overhang_m = 1.0

    [clock]
    max_gap_s = 0.5
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from evoeye.ads.messages import PLANNING_DECISIONS


class MappingError(ValueError):
    """A topic mapping file that cannot be used."""


@dataclass(frozen=True)
class Topics:
    """Topic per role. Required: odometry, objects, predicted, trajectory, control; "" = off."""

    odometry: str = "/localization/kinematic_state"  # nav_msgs/Odometry, base_link = rear axle
    acceleration: str = "/localization/acceleration"  # AccelWithCovarianceStamped
    objects: str = "/perception/object_recognition/tracking/objects"  # TrackedObjects
    predicted: str = "/perception/object_recognition/objects"  # PredictedObjects
    trajectory: str = "/planning/scenario_planning/trajectory"  # Trajectory
    control: str = "/control/command/control_cmd"  # Control
    velocity_limit: str = "/planning/scenario_planning/max_velocity"  # VelocityLimit
    mrm_state: str = "/api/fail_safe/mrm_state"  # MrmState: an MRM is an emergency brake
    ground_truth_objects: str = "/simulation/ground_truth/objects"  # TrackedObjects, true poses
    ground_truth_ego: str = "/simulation/ground_truth/ego"  # Odometry, true ego pose
    collision: str = "/simulation/ground_truth/collision"  # std_msgs/Bool, True while colliding


REQUIRED_ROLES = ("odometry", "objects", "predicted", "trajectory", "control")
DEFAULT_FACTORS = {  # planning factor topic → evoeye planning decision while it has a factor
    "/planning/planning_factors/obstacle_stop": "yield",
    "/planning/planning_factors/obstacle_cruise": "follow",
    "/planning/planning_factors/intersection": "proceed",
}


@dataclass(frozen=True)
class Vehicle:
    """The ego's box and command scale (Autoware's vehicle_info; defaults: evoeye's ego)."""

    length_m: float = 5.0
    width_m: float = 2.0
    rear_overhang_m: float = 1.0  # rear bumper to rear axle: base_link sits this far in
    accel_max_mps2: float = 3.0  # acceleration command of full throttle
    accel_min_mps2: float = -8.0  # acceleration command of full brake

    @property
    def centre_ahead_m(self) -> float:
        """How far the body centre is ahead of base_link (the rear-axle centre)."""
        return 0.5 * self.length_m - self.rear_overhang_m


@dataclass(frozen=True)
class Mapping:
    """Everything an import needs to know about one stack's recordings."""

    topics: Topics = field(default_factory=Topics)
    planning_factors: dict[str, str] = field(default_factory=lambda: dict(DEFAULT_FACTORS))
    vehicle: Vehicle = field(default_factory=Vehicle)
    rate_hz: float = 20.0  # the frame clock
    max_gap_s: float = 0.5  # a required topic silent for longer rejects the bag

    def roles(self) -> dict[str, str]:
        """Topic → role for every topic switched on (factor topics: role `factor`)."""
        out = {getattr(self.topics, f.name): f.name for f in fields(Topics)
               if getattr(self.topics, f.name)}
        return {**out, **dict.fromkeys(self.planning_factors, "factor")}


def _merged(cls: type, current: Any, table: dict[str, Any], section: str) -> Any:
    known = {f.name: f.type for f in fields(cls)}
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise MappingError(f"[{section}] has unknown keys {unknown}; known: {sorted(known)}")
    try:
        values = {k: (str(v) if known[k] == "str" else float(v)) for k, v in table.items()}
    except (TypeError, ValueError) as e:
        raise MappingError(f"[{section}]: {e}") from None
    return replace(current, **values)


def load_mapping(path: str | Path | None, base: Mapping | None = None) -> Mapping:
    """The defaults (`base`: another stack's, e.g. Apollo's), overridden by the TOML file at
    `path` (None: the defaults). A base without planning-factor topics takes none."""
    mapping = base or Mapping()
    if path is None:
        return mapping
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise MappingError(f"{path}: {e}") from None
    unknown = sorted(set(data) - {"topics", "planning_factors", "vehicle", "clock"})
    if unknown:
        raise MappingError(f"{path}: unknown sections {unknown}")
    try:
        topics = _merged(Topics, mapping.topics, data.get("topics", {}), "topics")
        vehicle = _merged(type(mapping.vehicle), mapping.vehicle, data.get("vehicle", {}),
                          "vehicle")
        clock = data.get("clock", {})
        if set(clock) - {"max_gap_s", "rate_hz"}:
            raise MappingError("[clock] takes max_gap_s and rate_hz")
    except MappingError as e:
        raise MappingError(f"{path}: {e}") from None
    if "planning_factors" in data and not mapping.planning_factors:
        raise MappingError(f"{path}: [planning_factors]: this stack's decision is not on "
                           "factor topics")
    factors = {str(k): str(v)
               for k, v in data.get("planning_factors", mapping.planning_factors).items()}
    bad = {k: v for k, v in factors.items() if v not in PLANNING_DECISIONS}
    if bad:
        raise MappingError(f"{path}: [planning_factors] {bad}: decisions are {PLANNING_DECISIONS}")
    missing = [r for r in REQUIRED_ROLES if not getattr(topics, r)]
    if missing:
        raise MappingError(f"{path}: required topics switched off: {missing}")
    return Mapping(topics, factors, vehicle, float(clock.get("rate_hz", mapping.rate_hz)),
                   float(clock.get("max_gap_s", mapping.max_gap_s)))
