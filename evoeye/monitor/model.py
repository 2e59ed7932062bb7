"""FusionMonitor network (paper §IV-B): module encoders → frame block → temporal MLP → risk.

Read top to bottom:

1. `Normalizer` — per-feature mean / std fitted on the training frames, kept as buffers so a
   checkpoint carries its own input scaling.
2. `SetEncoder` — a shared MLP over each obstacle of a set, then attention pooling over the
   obstacles that exist (perception: 9 features per obstacle; prediction: K×2 flattened).
3. `FusionNet` — per frame, one encoder per module (perception, prediction, planning = plan +
   plan_info flattened, control), concatenated and fused by the frame MLP; the last L frame
   features are concatenated and mixed by the temporal MLP; a linear layer gives the logit.

Inputs are the warehouse's ego-relative frame features (`evoeye.store.features`), with the
context axis L after the batch axis; masks mark real obstacles, real plan points and real
context frames. Whatever sits in a masked-out slot never reaches the output: masked inputs are
replaced by zeros after normalisation and padded context frames get a zero frame feature.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
from torch import nn

from evoeye.monitor.inputs import ABLATIONS, MODULES
from evoeye.monitor.kinematics import (
    FRAME_KINEMATIC_FEATURES,
    KINEMATIC_FEATURES,
    frame_kinematics,
    obstacle_kinematics,
)
from evoeye.store.features import (
    CONTROL_FEATURES,
    FEATURES,
    PERCEPTION_FEATURES,
    PLAN_FEATURES,
    PLAN_INFO_FEATURES,
    PREDICTION_FEATURES,
    FeatureSpec,
    FrameFeatures,
)

# The tensors FusionNet.forward takes, in order (also the ONNX input names).
FRAME_INPUTS = ("perception", "perception_mask", "prediction", "prediction_mask", "plan",
                "plan_mask", "plan_info", "control")  # encode_frames' arguments, in order
INPUTS = (*FRAME_INPUTS, "context_mask")
MASK_VALUE = -1e9  # attention logit of an empty slot: finite, so an empty set gives no NaN


@dataclass(frozen=True)
class FusionConfig:
    """Sizes of the network and of its inputs; ≈ 24 K parameters with the defaults at L = 5."""

    context_len: int = 5  # L
    modules: tuple[str, ...] = MODULES
    max_obstacles: int = FEATURES.max_obstacles  # n
    pred_points: int = FEATURES.pred_points  # K
    plan_points: int = FEATURES.plan_points  # P
    obstacle_dim: int = 32  # perception / prediction set encoders
    plan_dim: int = 32
    control_dim: int = 16
    frame_hidden: int = 48
    frame_dim: int = 32  # D, one frame feature z_t
    temporal_hidden: int = 48
    temporal_dim: int = 32  # h_t
    dropout: float = 0.0  # on the frame feature z_t and on the temporal MLP's hidden layer
    # relative kinematics derived from the perception inputs (evoeye.monitor.kinematics)
    kinematics: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "modules", tuple(self.modules))
        unknown = set(self.modules) - set(MODULES)
        if unknown or not self.modules:
            raise ValueError(f"modules must be a non-empty subset of {MODULES}, got "
                             f"{self.modules}")
        if self.context_len < 1:
            raise ValueError(f"context length L must be at least 1, got {self.context_len}")
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError(f"dropout must be in [0, 1), got {self.dropout}")

    @classmethod
    def for_spec(cls, spec: FeatureSpec, **kwargs) -> FusionConfig:
        """A config whose input sizes match the warehouse's FeatureSpec."""
        return cls(max_obstacles=spec.max_obstacles, pred_points=spec.pred_points,
                   plan_points=spec.plan_points, **kwargs)

    def to_dict(self) -> dict:
        """Every field; `kinematics` only where it is on, so a network made before it keeps
        its checkpoint and version id."""
        d = asdict(self)
        d["modules"] = list(self.modules)
        if not self.kinematics:
            del d["kinematics"]
        return d


def mlp(sizes: list[int], last_relu: bool = True, dropout: float = 0.0) -> nn.Sequential:
    """Linear layers of the given sizes with ReLU between them (and after the last if asked),
    dropout after each hidden ReLU if asked."""
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        layers.append(nn.Linear(a, b))
        if last_relu or i < len(sizes) - 2:
            layers.append(nn.ReLU())
        if dropout > 0 and i < len(sizes) - 2:
            layers.append(nn.Dropout(dropout))
    return nn.Sequential(*layers)


class Normalizer(nn.Module):
    """x ↦ (x − mean) / std per feature; identity until `fit` is called."""

    def __init__(self, shape: tuple[int, ...]):
        super().__init__()
        self.register_buffer("mean", torch.zeros(shape))
        self.register_buffer("std", torch.ones(shape))

    def fit(self, values: np.ndarray) -> None:
        """Fit on (rows, *shape) values; a constant feature keeps std 1 (it normalises to 0)."""
        if len(values) == 0:
            return
        values = values.astype(np.float64)
        std = values.std(axis=0)
        self.mean.copy_(torch.from_numpy(values.mean(axis=0)).float())
        self.std.copy_(torch.from_numpy(np.where(std > 1e-6, std, 1.0)).float())

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return (x - self.mean) / self.std


class SetEncoder(nn.Module):
    """Shared MLP per set item + attention pooling over the items present: (…, n, F) → (…, D)."""

    def __init__(self, in_dim: int, dim: int):
        super().__init__()
        self.item = mlp([in_dim, dim, dim])
        self.attn = nn.Linear(dim, 1)  # one attention logit per item

    def forward(self, x: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        h = self.item(x)  # (…, n, D)
        logit = self.attn(h).squeeze(-1).masked_fill(~mask, MASK_VALUE)  # (…, n)
        weight = torch.softmax(logit, dim=-1) * mask  # an empty set: all weights 0
        return (weight.unsqueeze(-1) * h).sum(dim=-2)  # (…, D)


class FusionNet(nn.Module):
    """The FusionMonitor network: a window of L frames ↦ collision-risk logit."""

    def __init__(self, config: FusionConfig):
        super().__init__()
        self.config = c = config
        self.kinematic = c.kinematics and "perception" in c.modules
        n_kin = len(KINEMATIC_FEATURES) if self.kinematic else 0
        n_perc = len(PERCEPTION_FEATURES) + n_kin
        n_pred = c.pred_points * len(PREDICTION_FEATURES)
        n_plan = c.plan_points * (len(PLAN_FEATURES) + 1) + len(PLAN_INFO_FEATURES)  # + mask
        self.norm = nn.ModuleDict()
        self.encoders = nn.ModuleDict()
        widths = []
        if "perception" in c.modules:
            self.norm["perception"] = Normalizer((n_perc,))
            self.encoders["perception"] = SetEncoder(n_perc, c.obstacle_dim)
            widths.append(c.obstacle_dim)
        if self.kinematic:
            self.norm["kinematics"] = Normalizer((len(FRAME_KINEMATIC_FEATURES),))
            widths.append(len(FRAME_KINEMATIC_FEATURES))
        if "prediction" in c.modules:
            self.norm["prediction"] = Normalizer((n_pred,))
            self.encoders["prediction"] = SetEncoder(n_pred, c.obstacle_dim)
            widths.append(c.obstacle_dim)
        if "planning" in c.modules:
            self.norm["plan"] = Normalizer((c.plan_points, len(PLAN_FEATURES)))
            self.norm["plan_info"] = Normalizer((len(PLAN_INFO_FEATURES),))
            self.encoders["planning"] = mlp([n_plan, c.plan_dim, c.plan_dim])
            widths.append(c.plan_dim)
        if "control" in c.modules:
            self.norm["control"] = Normalizer((len(CONTROL_FEATURES),))
            self.encoders["control"] = mlp([len(CONTROL_FEATURES), c.control_dim, c.control_dim])
            widths.append(c.control_dim)
        self.frame = mlp([sum(widths), c.frame_hidden, c.frame_dim])
        self.frame_dropout = nn.Dropout(c.dropout)
        # + L: the context mask, so the start of a run (padded slots) is visible as such
        self.temporal = mlp([c.context_len * (c.frame_dim + 1), c.temporal_hidden,
                             c.temporal_dim], dropout=c.dropout)
        self.classifier = nn.Linear(c.temporal_dim, 1)

    def fit_normalizers(self, frames: FrameFeatures) -> None:
        """Fit every input normaliser on these frames (only obstacles and points present)."""
        a = frames.arrays()
        if "perception" in self.norm:
            perception, mask = a["perception"], a["perception_mask"]
            if self.kinematic:
                perception, frame = (x.numpy() for x in self._with_kinematics(
                    torch.from_numpy(perception).float(), torch.from_numpy(mask)))
                self.norm["kinematics"].fit(frame)
            self.norm["perception"].fit(perception[mask])
        if "prediction" in self.norm:
            pred = a["prediction"][a["prediction_mask"]]
            self.norm["prediction"].fit(pred.reshape(len(pred), -1) if len(pred) else pred)
        if "plan" in self.norm:
            has_plan = a["plan_mask"].any(axis=1)
            self.norm["plan"].fit(a["plan"][has_plan])
            self.norm["plan_info"].fit(a["plan_info"])
        if "control" in self.norm:
            self.norm["control"].fit(a["control"])

    def encode_frames(
        self, perception: torch.Tensor, perception_mask: torch.Tensor,
        prediction: torch.Tensor, prediction_mask: torch.Tensor, plan: torch.Tensor,
        plan_mask: torch.Tensor, plan_info: torch.Tensor, control: torch.Tensor,
    ) -> torch.Tensor:
        """Frame block: (…, n, F) module inputs → (…, D) frame features z_t, each frame on its
        own (leading axes (B, L) for windows, (N,) for frames)."""
        z = []
        if "perception" in self.encoders:
            if self.kinematic:  # (B, L, n, 9 + 7) and the frame's (B, L, 2)
                perception, frame = self._with_kinematics(perception, perception_mask)
            x = self.norm["perception"](perception)  # (B, L, n, 9)
            x = torch.where(perception_mask.unsqueeze(-1), x, 0.0)
            z.append(self.encoders["perception"](x, perception_mask))  # (B, L, Dₒ)
            if self.kinematic:
                z.append(self.norm["kinematics"](frame))
        if "prediction" in self.encoders:
            x = self.norm["prediction"](prediction.flatten(-2))  # (B, L, n, K·2)
            x = torch.where(prediction_mask.unsqueeze(-1), x, 0.0)
            z.append(self.encoders["prediction"](x, prediction_mask))  # (B, L, Dₒ)
        if "planning" in self.encoders:
            x = torch.where(plan_mask.unsqueeze(-1), self.norm["plan"](plan), 0.0)  # (B,L,P,7)
            x = torch.cat([x.flatten(-2), plan_mask.to(x.dtype),
                           self.norm["plan_info"](plan_info)], dim=-1)  # (B, L, P·8 + 6)
            z.append(self.encoders["planning"](x))  # (B, L, Dₚ)
        if "control" in self.encoders:
            z.append(self.encoders["control"](self.norm["control"](control)))  # (B, L, D꜀)
        return self.frame(torch.cat(z, dim=-1))  # (B, L, D)

    @staticmethod
    def _with_kinematics(perception: torch.Tensor,
                         mask: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The perception inputs with each obstacle's kinematics appended, and the frame's."""
        kin = obstacle_kinematics(perception)
        return torch.cat([perception, kin], dim=-1), frame_kinematics(kin, mask)

    def forward(
        self, perception: torch.Tensor, perception_mask: torch.Tensor,
        prediction: torch.Tensor, prediction_mask: torch.Tensor, plan: torch.Tensor,
        plan_mask: torch.Tensor, plan_info: torch.Tensor, control: torch.Tensor,
        context_mask: torch.Tensor,
    ) -> torch.Tensor:
        """(B, L, …) inputs (see INPUTS) → (B,) logits; sigmoid(logit) is the risk score."""
        z = self.encode_frames(perception, perception_mask, prediction, prediction_mask, plan,
                               plan_mask, plan_info, control)  # (B, L, D)
        return self.head(z, context_mask)

    def forward_frames(self, frames: list[torch.Tensor], inverse: torch.Tensor,
                       context_mask: torch.Tensor) -> torch.Tensor:
        """`forward` with each distinct frame encoded once: (U, …) frame inputs (FRAME_INPUTS
        order), the (B, L) row of each context slot among them and the (B, L) context mask →
        (B,) logits, the same as `forward` on the gathered windows."""
        z = self.encode_frames(*frames)  # (U, D)
        return self.head(z[inverse], context_mask)  # (B, L, D) → (B,)

    def head(self, z: torch.Tensor, context_mask: torch.Tensor) -> torch.Tensor:
        """Temporal block: (B, L, D) frame features z_t and the (B, L) context mask → (B,)
        logits. Frames are encoded independently, so a frame shared by several windows may be
        encoded once (FusionMonitor.score does)."""
        z = torch.where(context_mask.unsqueeze(-1), self.frame_dropout(z), 0.0)  # padded: 0
        z = torch.cat([z, context_mask.to(z.dtype).unsqueeze(-1)], dim=-1)  # (B, L, D + 1)
        h = self.temporal(z.flatten(1))  # (B, H_t)
        return self.classifier(h).squeeze(-1)  # (B,)

    def n_parameters(self) -> int:
        return sum(p.numel() for p in self.parameters())


def example_inputs(net: FusionNet, batch: int = 2) -> tuple[torch.Tensor, ...]:
    """Zero inputs of the right shapes and dtypes for a batch of `batch` windows."""
    c = net.config
    b, ell, n, k, p = batch, c.context_len, c.max_obstacles, c.pred_points, c.plan_points
    shapes = {
        "perception": (b, ell, n, len(PERCEPTION_FEATURES)),
        "perception_mask": (b, ell, n),
        "prediction": (b, ell, n, k, len(PREDICTION_FEATURES)),
        "prediction_mask": (b, ell, n),
        "plan": (b, ell, p, len(PLAN_FEATURES)),
        "plan_mask": (b, ell, p),
        "plan_info": (b, ell, len(PLAN_INFO_FEATURES)),
        "control": (b, ell, len(CONTROL_FEATURES)),
        "context_mask": (b, ell),
    }
    return tuple(torch.ones(shapes[name], dtype=torch.bool) if name.endswith("mask")
                 else torch.zeros(shapes[name]) for name in INPUTS)


__all__ = ["ABLATIONS", "FRAME_INPUTS", "INPUTS", "MODULES", "FusionConfig", "FusionNet",
           "example_inputs"]


def config_from_dict(d: dict) -> FusionConfig:
    """The inverse of FusionConfig.to_dict (unknown keys are an error)."""
    return FusionConfig(**{**d, "modules": tuple(d.get("modules", MODULES))})


