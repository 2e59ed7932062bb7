"""Relative kinematics of each perceived obstacle, derived inside the FusionMonitor's network.

An option of the network (`FusionConfig.kinematics`), off in every recipe before it. The
perception inputs hold each obstacle's relative position, velocity and size in the ego frame
(x forward, y left); a small MLP can in principle compute a time to collision from them, but a
ratio of two inputs is hard to learn from few examples, and the alarms that come in time are the
ones that read it. So the network is handed, per obstacle, what the TTC rule reads
(`evoeye.baselines.ttc`, corridor TTC), as plain functions of the same inputs — no ground truth,
nothing a live stack does not have:

    gap_m                 bumper gap |dx| − (l_ego + l)/2, ≥ 0
    lateral_gap_m         side gap |dy| − (w_ego + w)/2, ≥ 0
    closing_mps           −dvx·sign(dx): > 0 when the gap shrinks
    lateral_closing_mps   −dvy·sign(dy): > 0 when the side gap shrinks
    inv_ttc_hz            closing / gap for an obstacle in the ego's corridor (side gap below the
                          corridor margin), else 0; clipped to [0, 10]
    required_decel_mps2   closing² / (2·gap) in the corridor — the constant deceleration that
                          stops the closing in the gap; clipped to [0, 30]
    lateral_inv_ttc_hz    lateral closing / side gap (a cut-in's approach); clipped to [0, 10]

and, per frame, the largest `inv_ttc_hz` and `required_decel_mps2` over the obstacles present.
Gaps are floored at 0.5 m (0.2 m sideways) in the ratios, so a touching obstacle reads as the
clip. The context's frames carry the trend: a lead that brakes shows as a closing speed rising
from frame to frame. Torch operations only, so the ONNX export and `evoeye watch` carry it.
"""

from __future__ import annotations

import torch

from evoeye.ads.config import PlanningConfig
from evoeye.boxes import CORRIDOR_MARGIN_M
from evoeye.store.features import PERCEPTION_FEATURES

KINEMATIC_FEATURES = ("gap_m", "lateral_gap_m", "closing_mps", "lateral_closing_mps",
                      "inv_ttc_hz", "required_decel_mps2", "lateral_inv_ttc_hz")
FRAME_KINEMATIC_FEATURES = ("max_inv_ttc_hz", "max_required_decel_mps2")
EGO_LENGTH_M = PlanningConfig().ego_length_m  # the ego's footprint, as the ADS knows it
EGO_WIDTH_M = PlanningConfig().ego_width_m
MIN_GAP_M, MIN_LATERAL_GAP_M = 0.5, 0.2
MAX_INV_TTC_HZ, MAX_DECEL_MPS2 = 10.0, 30.0
_DX, _DY, _DVX, _DVY, _LENGTH, _WIDTH = (
    PERCEPTION_FEATURES.index(k)
    for k in ("dx_m", "dy_m", "dvx_mps", "dvy_mps", "length_m", "width_m"))


def obstacle_kinematics(perception: torch.Tensor) -> torch.Tensor:
    """(…, n, 9) raw perception inputs → (…, n, 7) KINEMATIC_FEATURES of each obstacle."""
    dx, dy = perception[..., _DX], perception[..., _DY]
    gap = (dx.abs() - (EGO_LENGTH_M + perception[..., _LENGTH]) / 2).clamp(min=0.0)
    side = (dy.abs() - (EGO_WIDTH_M + perception[..., _WIDTH]) / 2).clamp(min=0.0)
    closing = -perception[..., _DVX] * torch.sign(dx)
    side_closing = -perception[..., _DVY] * torch.sign(dy)
    in_corridor = (side < CORRIDOR_MARGIN_M).to(perception.dtype)
    approach = closing.clamp(min=0.0) * in_corridor
    inv_ttc = (approach / gap.clamp(min=MIN_GAP_M)).clamp(max=MAX_INV_TTC_HZ)
    decel = (approach * approach / (2 * gap.clamp(min=MIN_GAP_M))).clamp(max=MAX_DECEL_MPS2)
    side_inv = (side_closing.clamp(min=0.0) / side.clamp(min=MIN_LATERAL_GAP_M)).clamp(
        max=MAX_INV_TTC_HZ)
    return torch.stack([gap, side, closing, side_closing, inv_ttc, decel, side_inv], dim=-1)


def frame_kinematics(kinematics: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """(…, n, 7) obstacle kinematics and the (…, n) mask of obstacles present → (…, 2) the
    frame's FRAME_KINEMATIC_FEATURES (0 with no obstacle)."""
    i, d = KINEMATIC_FEATURES.index("inv_ttc_hz"), KINEMATIC_FEATURES.index("required_decel_mps2")
    present = kinematics[..., [i, d]] * mask.unsqueeze(-1).to(kinematics.dtype)
    return present.amax(dim=-2)


__all__ = ["FRAME_KINEMATIC_FEATURES", "KINEMATIC_FEATURES", "frame_kinematics",
           "obstacle_kinematics"]
