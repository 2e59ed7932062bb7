"""TTC baseline: time to collision with the perceived obstacles in the ego's path corridor.

Read from the last frame of each window (the ADS's perception at time t, ego frame: x forward,
y left). An obstacle is in the corridor when |dy| < (w_ego + w_obj)/2 + margin; its bumper gap
is |dx| − (l_ego + l_obj)/2 and its closing speed −dvx·sign(dx) (ahead and slower, or behind and
faster). TTC = gap / closing speed for closing obstacles in the corridor (0 once the footprints
touch), +inf otherwise; the risk is 1 / (1 + TTC/τ), so TTC = τ gives 0.5 and no conflict 0.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass

import numpy as np

from evoeye.ads.config import PlanningConfig
from evoeye.store.features import PERCEPTION_FEATURES
from evoeye.store.windows import Windows

DX, DY, DVX = (PERCEPTION_FEATURES.index(k) for k in ("dx_m", "dy_m", "dvx_mps"))
LENGTH, WIDTH = (PERCEPTION_FEATURES.index(k) for k in ("length_m", "width_m"))
EGO_LENGTH_M = PlanningConfig().ego_length_m  # the ego's footprint, as the ADS knows it
EGO_WIDTH_M = PlanningConfig().ego_width_m


def min_ttc_s(
    perception: np.ndarray,
    mask: np.ndarray,
    *,
    ego_length_m: float = EGO_LENGTH_M,
    ego_width_m: float = EGO_WIDTH_M,
    corridor_margin_m: float = 0.3,
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


def ttc_risk(ttc_s: np.ndarray, tau_s: float) -> np.ndarray:
    """Monotone map of TTC (s) into [0, 1]: 1 / (1 + TTC/τ); +inf → 0."""
    return 1.0 / (1.0 + np.asarray(ttc_s, dtype=np.float64) / tau_s)


@dataclass(frozen=True)
class TTCMonitor:
    """Rule-based monitor: risk from the minimum TTC of the last frame's perceived obstacles."""

    tau_s: float = 1.0
    corridor_margin_m: float = 0.3
    ego_length_m: float = EGO_LENGTH_M
    ego_width_m: float = EGO_WIDTH_M
    name: str = "ttc"
    context_len: int = 1  # reads only the newest frame of a window

    @property
    def version(self) -> str:
        digest = hashlib.sha256(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()
        return f"ttc-{digest[:10]}"

    def ttc_s(self, windows: Windows) -> np.ndarray:
        """(B,) min TTC in s at the newest frame of each window."""
        rows = windows.context[:, -1]
        return min_ttc_s(
            windows.features.perception[rows], windows.features.perception_mask[rows],
            ego_length_m=self.ego_length_m, ego_width_m=self.ego_width_m,
            corridor_margin_m=self.corridor_margin_m,
        )

    def score(self, windows: Windows) -> np.ndarray:
        return ttc_risk(self.ttc_s(windows), self.tau_s)
