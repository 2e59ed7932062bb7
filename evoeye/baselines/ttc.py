"""TTC baselines: time to collision with the perceived obstacles, in the ego's corridor (TTC)
and between oriented boxes in the plane (TTC-2D).

Both read the last frame of each window (the ADS's perception at time t, ego frame: x forward,
y left) and map TTC to risk as 1 / (1 + TTC/τ), so TTC = τ gives 0.5 and no conflict 0.

* TTC: an obstacle is in the corridor when |dy| < (w_ego + w_obj)/2 + margin; its bumper gap is
  |dx| − (l_ego + l_obj)/2 and its closing speed −dvx·sign(dx) (ahead and slower, or behind and
  faster). TTC = gap / closing speed for closing obstacles in the corridor (0 once the
  footprints touch), +inf otherwise. It ignores lateral motion and heading.
* TTC-2D (commonroad-crime's TTC*, with constant-velocity predictions): the time until the
  ego's box and an obstacle's oriented box (its perceived size and relative heading) first
  overlap, both keeping their velocity and heading — the obstacle moving at (dvx, dvy)
  relative to the ego — by the exact separating-axis sweep of `evoeye.boxes.first_contact_s`
  (TTC* checks the same overlap at each time step). 0 when they overlap now, +inf if never.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from typing import ClassVar

import numpy as np

from evoeye.ads.config import PlanningConfig
from evoeye.boxes import CORRIDOR_MARGIN_M, box_corners, first_contact_s
from evoeye.store.features import PERCEPTION_FEATURES
from evoeye.store.windows import Windows

DX, DY, DVX, DVY = (PERCEPTION_FEATURES.index(k) for k in ("dx_m", "dy_m", "dvx_mps", "dvy_mps"))
COS_DH, SIN_DH = (PERCEPTION_FEATURES.index(k) for k in ("cos_dheading", "sin_dheading"))
LENGTH, WIDTH = (PERCEPTION_FEATURES.index(k) for k in ("length_m", "width_m"))
EGO_LENGTH_M = PlanningConfig().ego_length_m  # the ego's footprint, as the ADS knows it
EGO_WIDTH_M = PlanningConfig().ego_width_m


def min_ttc_s(
    perception: np.ndarray,
    mask: np.ndarray,
    *,
    ego_length_m: float = EGO_LENGTH_M,
    ego_width_m: float = EGO_WIDTH_M,
    corridor_margin_m: float = CORRIDOR_MARGIN_M,
) -> np.ndarray:
    """(B,) smallest TTC in s over the obstacles (B, n, 9) with `mask` (B, n); +inf if none."""
    dx, dy, dvx = perception[..., DX], perception[..., DY], perception[..., DVX]
    half_len = (ego_length_m + perception[..., LENGTH]) / 2
    half_wid = (ego_width_m + perception[..., WIDTH]) / 2
    in_corridor = mask & (np.abs(dy) < half_wid + corridor_margin_m)
    gap_m = np.maximum(np.abs(dx) - half_len, 0.0)
    closing_mps = -dvx * np.sign(dx)
    touching = in_corridor & (gap_m <= 0.0)
    closing = in_corridor & (closing_mps > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ttc = np.where(closing, gap_m / np.where(closing, closing_mps, 1.0), np.inf)
    ttc = np.where(touching, 0.0, ttc)
    return ttc.min(axis=-1, initial=np.inf).astype(np.float64)


def min_ttc_2d_s(
    perception: np.ndarray,
    mask: np.ndarray,
    *,
    ego_length_m: float = EGO_LENGTH_M,
    ego_width_m: float = EGO_WIDTH_M,
) -> np.ndarray:
    """(B,) smallest TTC-2D in s over the obstacles (B, n, 9) with `mask` (B, n); +inf if none."""
    p = perception.astype(np.float64).reshape(-1, perception.shape[-1])  # (B·n, 9)
    other = box_corners(p[:, DX], p[:, DY], np.arctan2(p[:, SIN_DH], p[:, COS_DH]),
                        p[:, LENGTH], p[:, WIDTH])
    zero = np.zeros(1)
    ego = box_corners(zero, zero, zero, np.array([ego_length_m]), np.array([ego_width_m]))
    ttc = first_contact_s(np.broadcast_to(ego, other.shape), other, p[:, [DVX, DVY]])
    return np.where(mask, ttc.reshape(mask.shape), np.inf).min(axis=-1, initial=np.inf)


def rule_version(prefix: str, config: dict) -> str:
    """`<prefix>-<10 hex>`: a rule-based monitor's version, a hash of its parameters."""
    digest = hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()
    return f"{prefix}-{digest[:10]}"


def ttc_risk(ttc_s: np.ndarray, tau_s: float) -> np.ndarray:
    """Monotone map of TTC (s) into [0, 1]: 1 / (1 + TTC/τ); +inf → 0."""
    return 1.0 / (1.0 + np.asarray(ttc_s, dtype=np.float64) / tau_s)


@dataclass(frozen=True)
class NewestFrameTTC:
    """A TTC rule: risk from the smallest TTC over the obstacles perceived in the newest frame
    of each window; subclasses say how TTC is measured (`min_ttc_s`)."""

    tau_s: float = 1.0
    ego_length_m: float = EGO_LENGTH_M
    ego_width_m: float = EGO_WIDTH_M
    context_len: int = 1  # reads only the newest frame of a window
    version_prefix: ClassVar[str] = "ttc"

    @property
    def version(self) -> str:
        return rule_version(self.version_prefix, asdict(self))

    def min_ttc_s(self, perception: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """(B,) smallest TTC in s over the obstacles (B, n, 9) with `mask` (B, n)."""
        raise NotImplementedError

    def ttc_s(self, windows: Windows) -> np.ndarray:
        """(B,) min TTC in s at the newest frame of each window."""
        rows = windows.context[:, -1]
        return self.min_ttc_s(windows.features.perception[rows],
                              windows.features.perception_mask[rows])

    def score(self, windows: Windows) -> np.ndarray:
        return ttc_risk(self.ttc_s(windows), self.tau_s)


@dataclass(frozen=True)
class TTCMonitor(NewestFrameTTC):
    """Rule-based monitor: TTC of the obstacles in the ego's corridor."""

    corridor_margin_m: float = CORRIDOR_MARGIN_M
    name: str = "ttc"

    def min_ttc_s(self, perception: np.ndarray, mask: np.ndarray) -> np.ndarray:
        return min_ttc_s(perception, mask, ego_length_m=self.ego_length_m,
                         ego_width_m=self.ego_width_m, corridor_margin_m=self.corridor_margin_m)


@dataclass(frozen=True)
class TTC2DMonitor(NewestFrameTTC):
    """Rule-based monitor: TTC-2D, oriented boxes at constant velocity (commonroad-crime's
    TTC*)."""

    name: str = "ttc-2d"
    version_prefix: ClassVar[str] = "ttc2d"

    def min_ttc_s(self, perception: np.ndarray, mask: np.ndarray) -> np.ndarray:
        return min_ttc_2d_s(perception, mask, ego_length_m=self.ego_length_m,
                            ego_width_m=self.ego_width_m)
