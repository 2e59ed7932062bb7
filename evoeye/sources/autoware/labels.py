"""A frame's ground truth, and with it the collision label, from what the bag has of it.

In order of preference (`label_source`):
1. `collision_topic:<topic>` — a collision event topic (std_msgs/Bool, True while the ego is in a
   collision), as a simulator's scenario runner can publish it;
2. `ground_truth_objects:<topic>` — the simulator's true objects (TrackedObjects), checked every
   frame against the ego's footprint (its true pose from the ground-truth ego topic, else its
   localization, and the vehicle's length and width): touching or overlapping is a collision;
3. `none` — no ground truth: the run is unlabelled (never trained, calibrated or measured on).
A collision holds from its first frame on, as the simulator's own `crashed` flag does: only
the first collision time defines labels (Definition 1).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evoeye.boxes import box_corners, box_gaps
from evoeye.log.records import UNLABELLED
from evoeye.scene import EGO_ID
from evoeye.sources.autoware.config import Mapping
from evoeye.sources.autoware.convert import Ego


def label_source(mapping: Mapping, topics: set[str]) -> str:
    """What labels a bag with `topics` (module doc)."""
    t = mapping.topics
    if t.collision and t.collision in topics:
        return f"collision_topic:{t.collision}"
    if t.ground_truth_objects and t.ground_truth_objects in topics:
        return f"ground_truth_objects:{t.ground_truth_objects}"
    return UNLABELLED


@dataclass
class GroundTruth:
    """Builds the /sim/ground_truth message of each frame, remembering the first collision."""

    source: str
    length_m: float
    width_m: float
    collided: bool = False
    collision_actor: int = -1
    min_gap_m: float = float("inf")
    _gaps_known: bool = field(default=False, repr=False)

    def message(self, t_s: float, ego: Ego, ego_accel_mps2: float, objects: dict[str, Any] | None,
                colliding: bool | None, origin: tuple[float, float]) -> dict[str, Any]:
        """The frame's ground truth: the ego first (actor 0), then the true objects if any."""
        objs = objects if objects is not None and self.source != UNLABELLED else None
        n = 0 if objs is None else len(objs["track_id"])
        x = np.array([ego.x_m, *(objs["x_m"] if n else ())])
        y = np.array([ego.y_m, *(objs["y_m"] if n else ())])
        h = np.array([ego.heading_rad, *(objs["heading_rad"] if n else ())])
        length = np.array([self.length_m, *(objs["length_m"] if n else ())])
        width = np.array([self.width_m, *(objs["width_m"] if n else ())])
        vx = np.array([ego.speed_mps * np.cos(ego.heading_rad), *(objs["vx_mps"] if n else ())])
        vy = np.array([ego.speed_mps * np.sin(ego.heading_rad), *(objs["vy_mps"] if n else ())])
        ids = [EGO_ID, *(objs["track_id"] if n else ())]
        touching = np.zeros(n, bool)
        if n:
            corners = box_corners(x, y, h, length, width)
            gaps = box_gaps(np.broadcast_to(corners[:1], corners[1:].shape), corners[1:])
            touching = gaps <= 0.0
            self.min_gap_m = min(self.min_gap_m, float(gaps.min()))
            self._gaps_known = True
        if not self.collided:
            if self.source.startswith("collision_topic:") and colliding:
                self.collided = True
                self.collision_actor = int(ids[1 + int(np.argmax(touching))]) if touching.any() \
                    else -1
            elif self.source.startswith("ground_truth_objects:") and touching.any():
                self.collided = True
                self.collision_actor = int(ids[1 + int(np.argmax(touching))])
        return {
            "t_s": t_s, "actor_id": ids,
            "x_m": (x - origin[0]).tolist(), "y_m": (y - origin[1]).tolist(),
            "heading_rad": h.tolist(), "speed_mps": np.hypot(vx, vy).tolist(),
            "vx_mps": vx.tolist(), "vy_mps": vy.tolist(),
            "accel_mps2": [ego_accel_mps2] + [0.0] * n,
            "length_m": length.tolist(), "width_m": width.tolist(),
            "crashed": [self.collided, *(touching & self.collided).tolist()],
            "ego_collision": self.collided, "collision_actor": self.collision_actor,
        }

    @property
    def min_distance_m(self) -> float | None:
        return self.min_gap_m if self._gaps_known else None
