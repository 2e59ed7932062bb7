"""Every tuning knob of the ADS, grouped per module, with units in the names.

The defaults describe a plausibly competent production stack, each imperfection a tunable source
of failure: a 360° lidar and a long-range radar that miss far and occluded cars, see boxes from
the visible points, merge close cars, report clutter and multipath ghosts, and hand over 250 ms
late (compensated by ego motion and track prediction); multi-modal prediction whose intents show
only once lateral motion or turning shows; planning under uncertainty with gap margins,
decision hysteresis, a comfort braking limit and a jerk-limited AEB; and actuators with lag and
a brake dead time. They are not tuned to collision-rate bands; tune with `dataclasses.replace`
on the group.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace


@dataclass(frozen=True)
class LocalizationConfig:
    """Gaussian noise on the ego's own state."""

    pos_sigma_m: float = 0.05
    heading_sigma_rad: float = 0.003
    speed_sigma_mps: float = 0.05
    accel_sigma_mps2: float = 0.1


@dataclass(frozen=True)
class SensorConfig:
    """The sensor set (360° lidar + long-range front radar), its errors, and the latency."""

    # lidar: 360°, detection probability falling with range (quadratic) and occlusion
    lidar_range_m: float = 75.0
    lidar_detect_prob_near: float = 0.98  # per-frame detection probability at zero range …
    lidar_detect_prob_far: float = 0.7  # … at the lidar's range
    occluded_fraction_max: float = 0.7  # the lidar's probability falls linearly to 0 here
    pos_sigma_m: float = 0.08  # lidar position noise at zero range …
    pos_sigma_per_m: float = 0.004  # … plus this much per metre of range
    vel_sigma_mps: float = 0.4  # lidar velocity (point flow) noise …
    vel_sigma_per_m: float = 0.01
    heading_sigma_rad: float = 0.02
    heading_sigma_per_m: float = 0.001
    lidar_depth_seen_frac: float = 0.8  # seen end-on, a box's depth is this fraction of the car
    lidar_merge_gap_m: float = 0.5  # segmentation merges objects whose boxes are this close
    # radar: long range, narrow, good range and range rate, poor azimuth (lateral) accuracy
    radar_range_m: float = 180.0
    radar_half_fov_rad: float = math.radians(12.0)
    radar_detect_prob_near: float = 0.95
    radar_detect_prob_far: float = 0.8
    radar_occluded_fraction_max: float = 1.0  # radar sees partly under and around cars
    radar_range_sigma_m: float = 0.3
    radar_azimuth_sigma_rad: float = 0.008  # ≈ 1.2 m across at 150 m
    radar_range_rate_sigma_mps: float = 0.15
    radar_vel_sigma_mps: float = 1.0  # of the velocity vector: the tangential part is unmeasured
    radar_length_m: float = 4.5  # box assumed for a radar-only detection
    radar_width_m: float = 1.9
    # false positives: short-lived clutter, and radar multipath ghosts mirrored at a guard-rail
    clutter_rate_per_frame: float = 0.5  # Poisson mean of clutter detections per frame
    clutter_max_per_frame: int = 4
    clutter_min_range_m: float = 5.0
    ghost_prob: float = 0.5  # per frame, per radar target beyond ghost_min_range_m
    ghost_min_range_m: float = 30.0
    ghost_rail_offset_m: float = 8.0  # the guard-rails' lateral distance from the ego
    latency_s: float = 0.25  # detections reach the tracker this long after capture (0.1–0.3 s)
    compensate_latency: bool = True  # publish tracks predicted forward to publication time


@dataclass(frozen=True)
class TrackerConfig:
    """Constant-velocity Kalman tracker with gated global-nearest-neighbour association."""

    gate_m: float = 4.0  # max distance between a predicted track and its detection
    confirm_hits: int = 3  # a track is published once it has this many hits (M)
    tentative_max_misses: int = 1  # an unconfirmed track dies after this many misses in a row
    max_coast_frames: int = 10  # a confirmed track is coasted this many missed frames, then dropped
    accel_noise_mps2: float = 3.0  # CV process noise (white acceleration σ)
    confidence_hits_scale: float = 2.0  # confidence rises as hits / (hits + scale)
    confidence_range_drop: float = 0.3  # confidence falls by this fraction at the front range
    confidence_coast_decay: float = 0.85  # confidence × decay^missed_frames


@dataclass(frozen=True)
class PredictionConfig:
    """Multi-modal prediction: lane keeping, lane changes and lane continuations, CV fallback."""

    horizon_s: float = 3.0
    dt_s: float = 0.1
    lane_match_radius_m: float = 3.0  # an obstacle farther than this from every lane centre is "cv"
    # lane-change intent: log-odds = v_lat / speed_scale + offset / offset_scale − bias
    intent_lat_speed_scale_mps: float = 0.4
    intent_offset_scale_m: float = 1.0
    intent_change_bias: float = 4.5  # prior against a lane change at zero evidence: a cut-in
    # becomes the likelier hypothesis only about half-way into the lane, as a production
    # stack's in-path selection has it
    lane_change_duration_s: float = 3.0  # predicted duration of a change over a whole lane
    # lane continuations (turns): heading vs each continuation's tangent a little ahead
    turn_lookahead_s: float = 1.0
    turn_lookahead_min_m: float = 5.0
    turn_heading_sigma_rad: float = 0.2
    successor_join_m: float = 1.5  # a lane starting this close to another's end continues it
    min_mode_prob: float = 0.05  # less probable modes are dropped (the best one always stays)
    # give way: a car on a lane that yields to the route (the map's rule of the road) is expected
    # to stop at the lane's end; the belief fades as the braking it would need to stop grows
    yield_prior: float = 0.9  # P(it stops) while it could still stop comfortably
    yield_decel_mps2: float = 4.0  # the braking a driver who means to stop would not exceed …
    yield_decel_scale_mps2: float = 0.5  # … logistic width of the fade around it
    yield_range_m: float = 60.0  # within this of the lane's end the hypothesis is made
    lane_resample_m: float = 1.0  # lane polylines are resampled to this spacing at start-up
    grid_cell_m: float = 1.0  # cell of the lookup grid used to project onto lanes


@dataclass(frozen=True)
class PlanningConfig:
    """Route following, IDM car following, gap acceptance, hysteresis and braking limits."""

    horizon_s: float = 4.0
    dt_s: float = 0.1
    ego_length_m: float = 5.0
    ego_width_m: float = 2.0
    corridor_margin_m: float = 0.3  # lateral margin added to both half-widths for "in path"
    max_obstacle_half_length_m: float = 3.0  # bounds the corridor search (route grid reach)
    mode_prob_min: float = 0.5  # plans against a track's best mode and any as likely as not
    idm_accel_mps2: float = 2.0  # IDM a: max acceleration
    idm_decel_mps2: float = 3.0  # IDM b: comfortable deceleration
    idm_delta: float = 4.0
    time_headway_s: float = 1.2  # IDM T
    min_gap_m: float = 3.0  # IDM s0, bumper to bumper
    follow_decel_max_mps2: float = 3.0  # following brakes harder only if the gap demands it …
    follow_soft_headway_s: float = 0.6  # … or the gap is below min_gap + v · this
    comfort_decel_mps2: float = 3.5  # no normal decision brakes harder; beyond it is AEB's job
    follow_range_m: float = 120.0  # leaders farther than this along the route are ignored
    cutin_horizon_s: float = 1.0  # an aligned car predicted in the path within this is a leader
    aligned_max_rad: float = 0.6  # heading gap to the route below which a car "follows"
    gap_margin_s: float = 0.5  # a crossing gap is taken only with this much time to spare …
    arrival_uncertainty_frac: float = 0.1  # … the other's arrival taken this much earlier
    go_accel_mps2: float = 2.0  # accel assumed for the ego's arrival estimate
    stop_buffer_m: float = 1.5  # the ego stops this far before a conflict region
    yield_decel_max_mps2: float = 1.75  # beyond this the ego is committed and goes on
    proceed_hold_margin_s: float = 0.5  # a proceed is revoked only if the gap is this much short
    release_frames: int = 6  # a yield / AEB is held until its conflict is clear this many frames
    emergency_ttc_s: float = 0.8  # time to collision below which the ego brakes hard (AEB)
    emergency_decel_mps2: float = 8.5  # AEB deceleration …
    emergency_jerk_mps3: float = 30.0  # … reached at this jerk
    aeb_on_predicted_crossings: bool = False  # AEB also for a crossing car only predicted to
    # enter the path (junction AEB); the default acts once it is in the path
    stitch_tolerance_mps: float = 1.0  # replan from the measured speed if the plan drifts more
    route_resample_m: float = 1.0
    grid_cell_m: float = 1.0


@dataclass(frozen=True)
class ControlConfig:
    """Pure pursuit on the plan, PID on speed with the planned acceleration fed forward."""

    vehicle_length_m: float = 5.0  # of the kinematic bicycle the command drives
    lookahead_min_m: float = 4.0
    lookahead_time_s: float = 0.6  # lookahead = max(min, time · speed)
    max_steering_rad: float = 0.5
    max_steering_rate_radps: float = 1.0
    accel_min_mps2: float = -8.0  # brake saturation
    accel_max_mps2: float = 3.0
    speed_kp: float = 1.0  # 1/s
    speed_ki: float = 0.2  # 1/s²
    speed_integral_max_mps: float = 2.0  # anti-windup bound on the integrated speed error
    accel_lag_s: float = 0.25  # first-order lag of the powertrain / brakes (time constant)
    steering_lag_s: float = 0.15  # first-order lag of the steering actuator
    brake_dead_time_s: float = 0.1  # more braking takes effect only this long after it is asked


@dataclass(frozen=True)
class ADSConfig:
    """All knobs of the stack; `cruise_speed_mps` is the per-run set speed."""

    cruise_speed_mps: float = 25.0
    frame_dt_s: float = 0.05  # the ADS runs at 20 Hz
    localization: LocalizationConfig = field(default_factory=LocalizationConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    tracker: TrackerConfig = field(default_factory=TrackerConfig)
    prediction: PredictionConfig = field(default_factory=PredictionConfig)
    planning: PlanningConfig = field(default_factory=PlanningConfig)
    control: ControlConfig = field(default_factory=ControlConfig)

    @classmethod
    def cautious(cls) -> ADSConfig:
        """A more careful stack: 100 ms latency, conservative gap acceptance, an earlier AEB.

        Collides far less often than the defaults; unit tests pin it to test mechanisms
        independently of the tuned defaults.
        """
        return cls(
            sensor=SensorConfig(latency_s=0.10),
            prediction=PredictionConfig(intent_change_bias=2.0),
            planning=PlanningConfig(mode_prob_min=0.2, cutin_horizon_s=2.0,
                                    aeb_on_predicted_crossings=True,
                                    time_headway_s=1.5, gap_margin_s=1.0,
                                    arrival_uncertainty_frac=0.2, go_accel_mps2=1.5,
                                    yield_decel_max_mps2=5.0, comfort_decel_mps2=4.0,
                                    emergency_ttc_s=1.2),
        )

    def with_cruise_speed(self, cruise_speed_mps: float) -> ADSConfig:
        """The same configuration with another set speed."""
        return replace(self, cruise_speed_mps=float(cruise_speed_mps))
