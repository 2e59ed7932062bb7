"""Control: pure pursuit on the planned path; PID on speed, the planned acceleration fed forward.

The actuators are part of the module: the command it publishes (and the world applies) is the
realised one, after a brake dead time (more braking than `brake_dead_time_s` ago takes effect only
then; releasing is immediate) and a first-order lag on acceleration and on steering. So an AEB
decision reaches full deceleration only after dead time + ~2 τ, as in a real car.

The command drives highway-env's kinematic bicycle (reference point at the centre, slip angle
β = atan(½·tan δ), heading rate v·sin β / (L/2)); its centre moves on a circle of curvature
κ = 2·sin β / L, so pure pursuit's κ = 2·sin α / d maps to β = asin(κ·L/2), δ = atan(2·tan β),
with α measured from the direction of travel h + β.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Protocol

import numpy as np

from evoeye.ads.config import ControlConfig
from evoeye.ads.messages import ControlCommand, Localization, PlannedTrajectory

STOPPED_MPS = 0.05  # a planned speed at or below this is "hold still"


class Controller(Protocol):
    """Turns the planned trajectory into an actuator command."""

    def control(self, plan: PlannedTrajectory, ego: Localization) -> ControlCommand: ...


def _clamp(value: float, lo: float, hi: float) -> float:
    return lo if value < lo else hi if value > hi else value


def _lag_gain(dt_s: float, tau_s: float) -> float:
    """The per-step gain of a first-order lag with time constant tau_s (1: no lag)."""
    return 1.0 - math.exp(-dt_s / tau_s) if tau_s > 0.0 else 1.0


class PurePursuitController:
    """Pure pursuit + PID, with steering angle/rate limits, accel saturation and actuator lag."""

    def __init__(self, config: ControlConfig, dt_s: float) -> None:
        self.c = config
        self.dt_s = dt_s
        self._steering_cmd_rad = 0.0  # the rate-limited steering request
        self._steering_rad = 0.0  # the realised (lagged) steering angle
        self._accel_mps2 = 0.0  # the realised (lagged) acceleration
        self._speed_error_integral = 0.0
        # exact discretisation of the first-order lags: x += (target − x)·(1 − e^(−dt/τ))
        self._accel_gain = _lag_gain(dt_s, config.accel_lag_s)
        self._steering_gain = _lag_gain(dt_s, config.steering_lag_s)
        dead_frames = max(0, round(config.brake_dead_time_s / dt_s))
        self._requests: deque[float] = deque([0.0] * (dead_frames + 1), maxlen=dead_frames + 1)

    def _target(self, plan: PlannedTrajectory, lookahead_m: float) -> tuple[float, float]:
        """The point lookahead_m along the planned path (extended straight past its end)."""
        x, y = plan.x_m, plan.y_m
        arc = np.hypot(x[1:] - x[:-1], y[1:] - y[:-1]).cumsum()  # (P-1,) arc length at 1, 2, …
        i = int(arc.searchsorted(lookahead_m))
        if i < len(arc):  # between points i and i + 1
            a0 = float(arc[i - 1]) if i else 0.0
            a1 = float(arc[i])
            f = (lookahead_m - a0) / (a1 - a0) if a1 - a0 > 1e-9 else 1.0
            x0, y0, x1, y1 = float(x[i]), float(y[i]), float(x[i + 1]), float(y[i + 1])
            return x0 + (x1 - x0) * f, y0 + (y1 - y0) * f
        h = float(plan.heading_rad[-1])
        rest = lookahead_m - (float(arc[-1]) if len(arc) else 0.0)
        return float(x[-1]) + rest * math.cos(h), float(y[-1]) + rest * math.sin(h)

    def control(self, plan: PlannedTrajectory, ego: Localization) -> ControlCommand:
        c = self.c
        dt = self.dt_s
        v = ego.speed_mps

        # lateral: pure pursuit
        tx, ty = self._target(plan, max(c.lookahead_min_m, c.lookahead_time_s * abs(v)))
        beta = math.atan(0.5 * math.tan(self._steering_rad))
        dx, dy = tx - ego.x_m, ty - ego.y_m
        alpha = math.atan2(dy, dx) - (ego.heading_rad + beta)
        alpha = (alpha + math.pi) % (2.0 * math.pi) - math.pi
        kappa = 2.0 * math.sin(alpha) / max(math.hypot(dx, dy), 1e-3)
        beta_cmd = math.asin(_clamp(0.5 * kappa * c.vehicle_length_m, -0.99, 0.99))
        steer = math.atan(2.0 * math.tan(beta_cmd))
        step = c.max_steering_rate_radps * dt
        steer = _clamp(steer, self._steering_cmd_rad - step, self._steering_cmd_rad + step)
        steer = _clamp(steer, -c.max_steering_rad, c.max_steering_rad)
        self._steering_cmd_rad = steer
        steer = self._steering_rad + (steer - self._steering_rad) * self._steering_gain
        self._steering_rad = steer

        # longitudinal: feed-forward + PID on the plan's current speed
        v_ref = float(plan.speed_mps[0])
        a_ff = float(plan.accel_mps2[0])
        if v_ref <= STOPPED_MPS and a_ff <= 0.0:  # hold: bring the speed exactly to zero
            self._speed_error_integral = 0.0
            accel = -v / dt
        else:
            err = v_ref - v
            integral = _clamp(self._speed_error_integral + err * dt, -c.speed_integral_max_mps,
                              c.speed_integral_max_mps)
            accel = a_ff + c.speed_kp * err + c.speed_ki * integral
            if c.accel_min_mps2 < accel < c.accel_max_mps2:  # anti-windup: integrate if unsaturated
                self._speed_error_integral = integral
        accel = self._actuate(_clamp(accel, c.accel_min_mps2, c.accel_max_mps2), v)
        return ControlCommand(
            t_s=plan.t_s,
            throttle=accel / c.accel_max_mps2 if accel > 0.0 else 0.0,
            brake=accel / c.accel_min_mps2 if accel < 0.0 else 0.0,
            steering_rad=steer,
            accel_cmd_mps2=accel,
        )

    def _actuate(self, request_mps2: float, v_mps: float) -> float:
        """The acceleration realised this frame for the request: dead time on more braking,
        then the first-order lag; brakes stop the car but never reverse it."""
        self._requests.append(request_mps2)
        target = max(request_mps2, min(self._requests[0], 0.0))  # braking builds up late
        a = self._accel_mps2 + (target - self._accel_mps2) * self._accel_gain
        if a < 0.0:
            a = max(a, -max(v_mps, 0.0) / self.dt_s)
        self._accel_mps2 = a
        return a
