"""The ADS under monitoring: localization → perception → prediction → planning → control."""

from __future__ import annotations

import numpy as np

from evoeye.ads.config import ADSConfig
from evoeye.ads.control import Controller, PurePursuitController
from evoeye.ads.localization import Localizer, NoisyLocalizer
from evoeye.ads.messages import FrameMessages
from evoeye.ads.perception import Perception, TrackingPerception
from evoeye.ads.planning import Planner, RoutePlanner
from evoeye.ads.prediction import IntentPredictor, Predictor
from evoeye.scene import RoadMap, SceneState


class ADS:
    """The modular stack; `step` once per frame (20 Hz) with the ground-truth scene.

    Only perception (and localization, for the ego) reads the scene; each later module reads the
    message of the one before it, the ego's `Localization` and the static `RoadMap`. The modules
    are public attributes, so any of them can be swapped for another implementation of its
    Protocol. All randomness comes from `rng`: the same seed gives bit-identical messages.
    """

    def __init__(
        self, road_map: RoadMap, rng: np.random.Generator, config: ADSConfig | None = None
    ) -> None:
        c = config or ADSConfig()
        self.config = c
        self.road_map = road_map
        self.localizer: Localizer = NoisyLocalizer(c.localization, rng)
        self.perception: Perception = TrackingPerception(c.sensor, c.tracker, c.frame_dt_s, rng)
        self.predictor: Predictor = IntentPredictor(road_map, c.prediction)
        self.planner: Planner = RoutePlanner(road_map, c.planning, c.cruise_speed_mps, c.frame_dt_s)
        self.controller: Controller = PurePursuitController(c.control, c.frame_dt_s)

    def step(self, scene: SceneState) -> FrameMessages:
        """All module outputs for this frame; `control` is to be applied to the ego for dt."""
        ego = self.localizer.localize(scene)
        obstacles = self.perception.perceive(scene, ego)
        predictions = self.predictor.predict(obstacles, ego)
        plan = self.planner.plan(predictions, ego)
        control = self.controller.control(plan, ego)
        return FrameMessages(ego, obstacles, predictions, plan, control)
