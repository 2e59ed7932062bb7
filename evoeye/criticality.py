"""How close a run came to a collision, frame by frame, from its ground truth: the judge of
whether an intervention was needed (the supervisor's, `evoeye.evaluation.supervision`), and a
target a monitor can learn (`TrainParams.target = "critical"`, `evoeye.monitor.lookahead`).

Pure numpy over ground-truth scenes, beside `evoeye.scene` and `evoeye.boxes`: every layer that
holds scenes may judge them.

An AEB engineer does not call a brake on a near miss a nuisance. So an intervention at frame k
is *justified* when the unsupervised run, within H after k, collides (Definition 1's label) or
comes *critically close*:

* ground-truth TTC-2D < `critical_ttc_s` (1.5 s): the ego's box and another actor's, both
  keeping their velocity and heading, would touch that soon (`boxes.first_contact_s`, the
  exact sweep the TTC-2D baseline runs on perceived boxes, here on the true ones);
* or a required deceleration > `critical_decel_mps2` (4 m/s², beyond the ADS's 3.5 m/s² comfort
  limit): for the actors ahead in the ego's corridor, the larger of DRAC (closing speed² over
  twice the bumper gap: the lead keeps its speed) and the deceleration that stops the ego
  behind a lead braking to a stop at its present deceleration. Both are lower bounds of what
  avoiding it really takes, so "critical" errs towards calling a brake a nuisance.

A frame is *in conflict* — part of a hazardous encounter — at looser bounds (TTC-2D <
`conflict_ttc_s`, 3 s, or required deceleration > `conflict_decel_mps2`, 2 m/s²). A *safe
hazardous encounter* is a maximal stretch of conflict frames before any collision that never
turns critical and has no collision within H: the situations (a braking lead, a cut-in) a
trigger must ride through without braking. False interventions are reported per hour of safe
driving and per safe hazardous encounter.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from evoeye.boxes import CORRIDOR_MARGIN_M, box_corners, first_contact_s
from evoeye.scene import SceneState


@dataclass(frozen=True)
class Criticality:
    """The thresholds of the module doc (recorded with every supervision)."""

    critical_ttc_s: float = 1.5
    critical_decel_mps2: float = 4.0
    conflict_ttc_s: float = 3.0
    conflict_decel_mps2: float = 2.0

    def __post_init__(self) -> None:
        if not (0 < self.critical_ttc_s <= self.conflict_ttc_s
                and 0 < self.conflict_decel_mps2 <= self.critical_decel_mps2):
            raise ValueError(f"criticality bounds: 0 < critical TTC <= conflict TTC and "
                             f"0 < conflict decel <= critical decel, got {self}")

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class FrameRisk:
    """Per frame of a run: ground-truth TTC-2D (s, inf without conflict) and required
    deceleration (m/s², 0 without a closing lead)."""

    ttc_s: np.ndarray  # (F,)
    decel_mps2: np.ndarray  # (F,)

    def critical(self, c: Criticality) -> np.ndarray:  # (F,) bool
        return (self.ttc_s < c.critical_ttc_s) | (self.decel_mps2 > c.critical_decel_mps2)

    def conflict(self, c: Criticality) -> np.ndarray:  # (F,) bool
        return (self.ttc_s < c.conflict_ttc_s) | (self.decel_mps2 > c.conflict_decel_mps2)

    def ratio(self, c: Criticality) -> np.ndarray:  # (F,) ≥ 0
        """How close each frame is to critical: the larger of critical TTC / TTC and required
        deceleration / critical deceleration (1 at the bounds, > 1 where `critical` holds)."""
        with np.errstate(divide="ignore"):
            ttc = np.where(self.ttc_s > 0, c.critical_ttc_s / self.ttc_s, np.inf)
        return np.maximum(ttc, self.decel_mps2 / c.critical_decel_mps2)


def scene_risk(scene: SceneState) -> tuple[float, float]:
    """(TTC-2D in s, required deceleration in m/s²) of the ego (row 0) against every other
    actor of one ground-truth scene."""
    if scene.n < 2:
        return float("inf"), 0.0
    rel = scene.relative_to_ego()
    dx, dy, dvx, dvy, dh = rel.dx_m, rel.dy_m, rel.dvx_mps, rel.dvy_mps, rel.dheading_rad
    other = box_corners(dx, dy, dh, scene.length_m[1:], scene.width_m[1:])
    zero = np.zeros(1)
    ego = box_corners(zero, zero, zero, scene.length_m[:1], scene.width_m[:1])
    ttc = first_contact_s(np.broadcast_to(ego, other.shape), other, np.stack([dvx, dvy], -1))
    # the corridor ahead: longitudinal gap, closing speed, the lead's own deceleration
    ahead = (dx > 0) & (np.abs(dy) < (scene.width_m[0] + scene.width_m[1:]) / 2
                        + CORRIDOR_MARGIN_M)
    gap = np.maximum(dx - (scene.length_m[0] + scene.length_m[1:]) / 2, 0.05)
    closing = np.maximum(-dvx, 0.0)
    drac = closing**2 / (2 * gap)
    lead_speed = np.maximum(scene.speed_mps[1:] * np.cos(dh), 0.0)
    lead_decel = np.maximum(-scene.accel_mps2[1:] * np.cos(dh), 0.0)
    ego_speed = max(float(scene.speed_mps[0]), 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        stop_gap = gap + np.where(lead_decel > 0, lead_speed**2 / (2 * lead_decel), np.inf)
        stop = np.where(lead_decel > 0, ego_speed**2 / (2 * stop_gap), 0.0)
    need = np.where(ahead, np.maximum(drac, stop), 0.0)
    return float(ttc.min(initial=np.inf)), float(need.max(initial=0.0))


def frame_risk(scenes: list[SceneState]) -> FrameRisk:
    """`scene_risk` of every frame of a run, the same numbers: for frames with one actor count
    as one array program over (frames, actors), else frame by frame."""
    n = scenes[0].n if scenes else 0
    if n < 2 or len(scenes) < 2 or any(s.n != n for s in scenes):
        pairs = np.array([scene_risk(s) for s in scenes], dtype=np.float64).reshape(-1, 2)
        return FrameRisk(pairs[:, 0], pairs[:, 1])
    return FrameRisk(*_stacked_risk(scenes))


def _stacked_risk(scenes: list[SceneState]) -> tuple[np.ndarray, np.ndarray]:
    """`scene_risk` over F scenes of n ≥ 2 actors each: elementwise what it does per scene, on
    (F, n − 1) arrays, its scalar steps (the ego's heading and speed) still scalar per frame."""
    def col(name: str) -> np.ndarray:
        return np.array([getattr(s, name) for s in scenes], dtype=np.float64)  # (F, n)

    x, y, h = col("x_m"), col("y_m"), col("heading_rad")
    speed, accel, length, width = col("speed_mps"), col("accel_mps2"), col("length_m"), \
        col("width_m")
    vx = np.array([s.vx_mps for s in scenes])
    vy = np.array([s.vy_mps for s in scenes])
    h0 = [float(v) for v in h[:, 0]]  # scalar, as `relative_to_ego` takes it
    c = np.array([np.cos(v) for v in h0])[:, None]
    sn = np.array([np.sin(v) for v in h0])[:, None]
    ddx, ddy = x[:, 1:] - x[:, :1], y[:, 1:] - y[:, :1]
    rvx, rvy = vx[:, 1:] - vx[:, :1], vy[:, 1:] - vy[:, :1]
    dx, dy = c * ddx + sn * ddy, -sn * ddx + c * ddy
    dvx, dvy = c * rvx + sn * rvy, -sn * rvx + c * rvy
    dh = (h[:, 1:] - np.array(h0)[:, None] + np.pi) % (2 * np.pi) - np.pi
    f, m = dx.shape
    other = box_corners(dx.ravel(), dy.ravel(), dh.ravel(), length[:, 1:].ravel(),
                        width[:, 1:].ravel()).reshape(f, m, 4, 2)
    zero = np.zeros(f)
    ego = box_corners(zero, zero, zero, length[:, 0], width[:, 0])[:, None]  # (F, 1, 4, 2)
    ttc = first_contact_s(np.broadcast_to(ego, other.shape), other, np.stack([dvx, dvy], -1))
    ahead = (dx > 0) & (np.abs(dy) < (width[:, :1] + width[:, 1:]) / 2 + CORRIDOR_MARGIN_M)
    gap = np.maximum(dx - (length[:, :1] + length[:, 1:]) / 2, 0.05)
    closing = np.maximum(-dvx, 0.0)
    drac = closing**2 / (2 * gap)
    lead_speed = np.maximum(speed[:, 1:] * np.cos(dh), 0.0)
    lead_decel = np.maximum(-accel[:, 1:] * np.cos(dh), 0.0)
    ego_sq = np.array([max(float(v), 0.0) ** 2 for v in speed[:, 0]])[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        stop_gap = gap + np.where(lead_decel > 0, lead_speed**2 / (2 * lead_decel), np.inf)
        stop = np.where(lead_decel > 0, ego_sq / (2 * stop_gap), 0.0)
    need = np.where(ahead, np.maximum(drac, stop), 0.0)
    return ttc.min(axis=1, initial=np.inf), need.max(axis=1, initial=0.0)


def peak_risk(scenes: list[SceneState], c: Criticality | None = None) -> float:
    """A run's peak `FrameRisk.ratio` over its scenes (0 for none): a continuous level of how
    near it came to a collision (> 1: it turned critical). Pass the frames before a collision
    only; the collision itself is the top level."""
    if not scenes:
        return 0.0
    return float(frame_risk(scenes).ratio(c or Criticality()).max())


def justified_frames(label: np.ndarray, critical: np.ndarray, horizon_frames: int) -> np.ndarray:
    """(E,) bool: an intervention at frame k is justified (module doc) — its label is 1, or a
    critical frame lies in [k, k + horizon_frames]. `label` (E,) over the eligible frames,
    `critical` (≥ E,) over the run's frames."""
    e = len(label)
    crit = np.asarray(critical[:e], dtype=np.int64)
    # critical frames in the window [k, k + h]: a suffix-sum difference
    tail = np.concatenate([np.cumsum(crit[::-1])[::-1], [0]])  # tail[k] = crit[k:].sum()
    k = np.arange(e)
    ahead = tail[k] - tail[np.minimum(k + horizon_frames + 1, e)]
    return (np.asarray(label, bool)) | (ahead > 0)


def safe_encounters(conflict: np.ndarray, justified: np.ndarray) -> int:
    """Maximal stretches of conflict frames (over the eligible frames) with no justified
    frame: the hazardous encounters that ended safely."""
    e = len(justified)
    c = np.asarray(conflict[:e], bool)
    if not c.any():
        return 0
    edges = np.flatnonzero(np.diff(np.concatenate([[0], c.astype(np.int8), [0]])))
    starts, stops = edges[::2], edges[1::2]
    return int(sum(not justified[a:b].any() for a, b in zip(starts, stops, strict=True)))
