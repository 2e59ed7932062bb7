"""Pop-in: actors that first appear after the start of a run, close to the ego.

Every actor must exist from the first frame or enter from beyond the ego's sensor range; one
whose first frame is later and lies within `radius_m` of the ego appeared out of nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evoeye.evaluation.audit.tracks import Tracks

POP_IN_RADIUS_M = 70.0


@dataclass(frozen=True)
class Appearance:
    """An actor's first frame after t = 0 and its centre distance to the ego there."""

    actor_id: int
    t_s: float
    dist_m: float

    def to_dict(self) -> dict[str, float | int]:
        return {"actor_id": self.actor_id, "t_s": self.t_s, "dist_m": self.dist_m}


def late_appearances(tracks: Tracks) -> tuple[Appearance, ...]:
    """Every actor whose first frame is not the run's first frame, where it appeared."""
    present = tracks.present
    first = np.argmax(present, axis=0)  # (A,) first frame per actor (every actor has one)
    late = np.flatnonzero(first > 0)
    dist = np.hypot(tracks.x_m[first[late], late] - tracks.x_m[first[late], 0],
                    tracks.y_m[first[late], late] - tracks.y_m[first[late], 0])
    return tuple(
        Appearance(int(tracks.actor_id[c]), float(tracks.t_s[first[c]]), float(d))
        for c, d in zip(late, dist, strict=True)
    )


def check_pop_in(tracks: Tracks, radius_m: float = POP_IN_RADIUS_M) -> tuple[Appearance, ...]:
    """The late appearances within radius_m of the ego."""
    return tuple(a for a in late_appearances(tracks) if a.dist_m <= radius_m)
