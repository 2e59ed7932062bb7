"""Perception: detections from the sensor set, delayed by the processing latency, then tracked."""

from __future__ import annotations

from collections import deque
from typing import Protocol

import numpy as np

from evoeye.ads.config import SensorConfig, TrackerConfig
from evoeye.ads.detections import Detections
from evoeye.ads.messages import Localization, Obstacles
from evoeye.ads.sensing import SensorModel
from evoeye.ads.tracking import HEADING, LENGTH, VX, VY, WIDTH, CVTracker, X, Y
from evoeye.scene import SceneState


class Perception(Protocol):
    """Turns the scene into tracked obstacles (the only module that reads the ground truth)."""

    def perceive(self, scene: SceneState, ego: Localization) -> Obstacles: ...


class TrackingPerception:
    """Sensor set → latency ring buffer → CV Kalman tracker; publishes confirmed tracks.

    The detections the tracker receives at t_s were captured `latency_s` earlier (rounded to whole
    frames) and placed in the world with the ego pose estimated at capture (ego-motion
    compensation). With `compensate_latency` the published tracks are predicted forward over the
    latency with their own constant-velocity model, so what remains is the unmodelled
    acceleration during it (≈ ½·a·latency²); without, positions lag the truth by about
    speed · latency. `Obstacles.t_s` is the publication time, so every message of a frame shares
    one time stamp. Detection geometry uses the ego's true pose: the sensors sit on the car.
    """

    def __init__(
        self, sensor: SensorConfig, tracker: TrackerConfig, dt_s: float, rng: np.random.Generator
    ) -> None:
        self.sensor = SensorModel(sensor, rng)
        self.tracker = CVTracker(tracker, dt_s)
        self.range_m = max(sensor.lidar_range_m, sensor.radar_range_m)
        self.latency_frames = max(0, round(sensor.latency_s / dt_s))
        self.lead_s = self.latency_frames * dt_s if sensor.compensate_latency else 0.0
        self._pending: deque[Detections] = deque(maxlen=self.latency_frames + 1)

    def perceive(self, scene: SceneState, ego: Localization) -> Obstacles:
        return self.track(scene, self.sensor.detect(scene, ego))

    def track(self, scene: SceneState, detections: Detections) -> Obstacles:
        """The tracks published at scene.t_s, given this frame's `detections` (the lockstep
        engine detects for a whole batch of runs at once and hands each run its own)."""
        self._pending.append(detections)
        if len(self._pending) == self._pending.maxlen:
            self.tracker.step(self._pending[0].z)
        trk = self.tracker
        rows = trk.confirmed.nonzero()[0]
        s = trk.state.take(rows, axis=1)  # (13, n), a C-ordered copy: every published row is
        # contiguous, which orjson writes whole (`state[:, rows]` is Fortran-ordered)
        if self.lead_s:
            s[X:VX] += s[VX:VY + 1] * self.lead_s  # predicted to the publication time
        return Obstacles(
            t_s=float(scene.t_s),
            track_id=trk.track_id[rows],
            obj_class=["car"] * len(rows),
            x_m=s[X],
            y_m=s[Y],
            heading_rad=s[HEADING],
            vx_mps=s[VX],
            vy_mps=s[VY],
            length_m=s[LENGTH],
            width_m=s[WIDTH],
            confidence=trk.confidence(s, self.range_m),
        )
