"""How a collision came about, from the run's ground truth: the mechanism a reviewer names first.

A collision run is put in one class, from the partner's motion relative to the ego over the
`LOOKBACK_S` before contact (ego frame: x along the ego's heading, y to its left):

* `struck-from-behind` — the partner hit the ego from behind (`struck_from_behind`);
* `crossing` — the partner's heading differs from the ego's by more than 30° at contact (a
  crossing or turning car: the intersection's conflicts);
* `cut-in` — the partner was ahead at contact but outside the ego's corridor at some frame of
  the last `CUT_IN_S` (it came in from the side);
* `braking-lead` — a lead in the corridor all along that braked harder than `BRAKING_MPS2` in
  the lookback (the ego ran into a car braking ahead of it);
* `slow-lead` — a lead in the corridor all along that did not brake so (the ego closed on a
  slower or stopped car);
* `other` — anything else (e.g. the partner left no trace in the lookback).

With the class come the partner's hardest braking in the lookback and when its braking began
(s before contact: the first frame of the last stretch below `BRAKING_MPS2`), which is how much
warning the scene itself gave.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from evoeye.boxes import CORRIDOR_MARGIN_M
from evoeye.sim.counterfactual import struck_from_behind
from evoeye.sim.episode import Episode

MECHANISMS = ("braking-lead", "slow-lead", "cut-in", "crossing", "struck-from-behind", "other")
LOOKBACK_S = 6.0
CUT_IN_S = 3.0
BRAKING_MPS2 = 2.0  # a deceleration beyond the ADS's gentle speed keeping
CROSSING_RAD = math.radians(30)


@dataclass(frozen=True)
class Mechanism:
    """A collision's mechanism (module doc)."""

    kind: str  # one of MECHANISMS
    partner_min_accel_mps2: float | None  # the partner's hardest braking in the lookback
    braking_onset_s: float | None  # s before contact its last braking stretch began

    def to_dict(self) -> dict:
        return asdict(self)


def mechanism(episode: Episode) -> Mechanism | None:
    """The mechanism of the episode's first collision; None without one."""
    o = episode.outcome
    if not o.collided or o.collision_time_s is None:
        return None
    if struck_from_behind(episode):
        return Mechanism("struck-from-behind", None, None)
    dt = 1.0 / episode.rate_hz
    contact = min(int(round(o.collision_time_s / dt)), len(episode.frames) - 1)
    first = max(0, contact - int(round(LOOKBACK_S / dt)))
    rows = []  # (t before contact, dx, dy, dheading, accel, half corridor) of the partner
    for k in range(first, contact + 1):
        sc = episode.frames[k].scene
        hit = np.flatnonzero(sc.actor_id == o.other_actor)
        if not hit.size:
            continue
        i = int(hit[0])
        rel = sc.relative_to_ego()  # rows 1…: the partner is row i − 1
        rows.append(((contact - k) * dt, rel.dx_m[i - 1], rel.dy_m[i - 1],
                     rel.dheading_rad[i - 1], float(sc.accel_mps2[i]),
                     (float(sc.width_m[0]) + float(sc.width_m[i])) / 2 + CORRIDOR_MARGIN_M))
    if not rows:
        return Mechanism("other", None, None)
    a = np.array(rows)  # (n, 6), oldest first; the last row is the contact
    before, dx, dy, dh, accel, half = a.T
    min_accel = float(accel.min())
    braking = accel < -BRAKING_MPS2
    onset = None
    if braking.any():
        start = int(np.flatnonzero(braking)[-1])
        while start > 0 and braking[start - 1]:
            start -= 1
        onset = float(before[start])
    if abs(dh[-1]) > CROSSING_RAD:
        kind = "crossing"
    elif dx[-1] <= 0:
        kind = "other"
    elif (np.abs(dy) >= half)[before <= CUT_IN_S].any():
        kind = "cut-in"
    else:
        kind = "braking-lead" if min_accel < -BRAKING_MPS2 else "slow-lead"
    return Mechanism(kind, min_accel, onset)
