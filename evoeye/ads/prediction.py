"""Prediction: a future trajectory for every tracked obstacle, lane-following or constant-velocity.

An obstacle gets the "lane" model when it sits near a lane centre and shows little lateral speed
relative to it; it then advances along that centre line at its current along-lane speed (the lane:
the nearest one heading roughly the obstacle's way). Otherwise it gets "cv" (constant
velocity). The imperfections are deliberate: a cut-in is only recognised once its lateral speed
exceeds `cutin_lat_speed_mps`; a car on a turning lane is predicted along whichever lane matches
best, and where lanes coincide (an intersection entry) that may be the straight one; and as the
map has no lane topology, a lane-following prediction runs straight on past the lane's end.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from evoeye.ads.config import PredictionConfig
from evoeye.ads.geometry import PolylineIndex
from evoeye.ads.messages import Localization, Obstacles, Predictions
from evoeye.scene import RoadMap

HEADING_SECTORS = 8  # the lane grid keeps the nearest lane per 45° heading sector
MODELS = ("cv", "lane")  # indexed by "follows a lane"


class Predictor(Protocol):
    """Predicts the future positions of tracked obstacles."""

    def predict(self, obstacles: Obstacles, ego: Localization) -> Predictions: ...


class LaneOrCVPredictor:
    """Lane-following prediction on the map's lanes, constant velocity as the fallback."""

    def __init__(self, road_map: RoadMap, config: PredictionConfig) -> None:
        self.c = config
        self.k = int(round(config.horizon_s / config.dt_s))
        self.t_s = (np.arange(self.k) + 1.0) * config.dt_s  # (K,)
        self.lanes = PolylineIndex.build(
            [lane.points for lane in road_map.lanes], config.lane_resample_m,
            config.lane_match_radius_m, config.grid_cell_m, HEADING_SECTORS,
        ) if road_map.lanes else None  # a map without lanes: everything is "cv"

    def predict(self, obstacles: Obstacles, ego: Localization) -> Predictions:
        c = self.c
        t = self.t_s
        ox, oy = obstacles.x_m, obstacles.y_m  # (n,)
        vx, vy = obstacles.vx_mps, obstacles.vy_mps
        x = ox[:, None] + vx[:, None] * t  # (n, K) constant velocity
        y = oy[:, None] + vy[:, None] * t
        n = len(ox)
        if n == 0 or self.lanes is None:
            return self._message(obstacles, x, y, ["cv"] * n)
        lanes = self.lanes
        # the nearest lane heading within about ±45° (at most ±67°) of the obstacle
        v = lanes.candidates(ox, oy, obstacles.heading_rad)  # (n,)
        g, lat, tx, ty = lanes.project(ox, oy, v)
        # "lane" when near the centre line and moving along it: a heading check is implied for
        # moving cars (|v_lat| small), and for slow ones both models predict nearly the same
        on_lane = (np.abs(lat) <= c.lane_offset_max_m) & (
            np.abs(vy * tx - vx * ty) <= c.cutin_lat_speed_mps
        )
        if np.count_nonzero(on_lane):
            v_along = np.maximum(vx * tx + vy * ty, 0.0)
            lx, ly = lanes.xy_at(g[:, None] + v_along[:, None] * t)  # (n, K)
            keep = on_lane[:, None]
            np.copyto(x, lx, where=keep)
            np.copyto(y, ly, where=keep)
        model = [MODELS[b] for b in on_lane.tolist()]
        return self._message(obstacles, x, y, model)

    def _message(
        self, obstacles: Obstacles, x: np.ndarray, y: np.ndarray, model: list[str]
    ) -> Predictions:
        return Predictions(
            t_s=obstacles.t_s, dt_s=self.c.dt_s, track_id=obstacles.track_id, model=model,
            length_m=obstacles.length_m, width_m=obstacles.width_m, x_m=x, y_m=y,
        )
