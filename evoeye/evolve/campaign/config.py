"""What an evolution campaign does: its configuration, validated, and the monitor-update options.

Every field of `CampaignConfig` but `budget_s` and `reference` enters the campaign id
(`Campaign.campaign_id`), so the same configuration resumes the same campaign.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import evoeye.baselines  # noqa: F401  (registers the baseline monitor families: aem, …)
from evoeye.evolve.campaign.scoring import FEEDBACK_MODES
from evoeye.evolve.search.strategies import STRATEGIES
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES, evolvable_families, family_of
from evoeye.scenarios import DEFAULT_DELTA, get_scenario
from evoeye.sim.runner import SimConfig
from evoeye.store import SplitSpec
from evoeye.store.windows import DEFAULT_HORIZON_S

UPDATE_MODES = ("finetune", "retrain")
MAX_RUN_S = SimConfig().duration_s  # no run lasts longer than this (20 s)
FINETUNE_EPOCHS, FINETUNE_PATIENCE = 10, 4


@dataclass(frozen=True)
class CampaignConfig:
    """What a campaign does. Every field but `budget_s` and `reference` is part of its id."""

    scenario: str
    strategy: str = "evoeye"
    budget_s: float = 600.0  # simulated seconds the acquired runs may use in total
    seed: int = 0
    monitor: str | None = None  # G_0; None: the newest from-scratch monitor of the scenario
    n_round: int = 20  # N_round: runs per round
    update: str = "finetune"
    epochs: int | None = None  # per update; None: 10 when fine-tuning, TrainParams' when not
    patience: int | None = None
    delta: float = DEFAULT_DELTA
    feedback: str = "raw"  # ŷ of f_r: "raw" scores or "prior-corrected" (see evolve.search.feedback)
    family: str = DEFAULT_FAMILY  # the monitor family evolved: "fusion", "aem" (AEM-Evo), …
    reference: str | None = None  # aem: the FusionMonitor G_0 whose Hard Set judges; None: newest
    horizon_s: float = DEFAULT_HORIZON_S
    splits: SplitSpec = field(default_factory=SplitSpec)
    max_run_s: float = MAX_RUN_S

    def __post_init__(self) -> None:
        get_scenario(self.scenario)
        if self.strategy not in STRATEGIES:
            raise ValueError(f"unknown strategy {self.strategy!r}; known: {sorted(STRATEGIES)}")
        if self.feedback not in FEEDBACK_MODES:
            raise ValueError(f"feedback must be one of {FEEDBACK_MODES}, got {self.feedback!r}")
        if self.family not in FAMILIES or not FAMILIES[self.family].evolvable:
            raise ValueError(f"family must be one of {evolvable_families()}, got "
                             f"{self.family!r}")
        if self.monitor and (of := family_of(self.monitor).name) != self.family:
            raise ValueError(f"G_0 {self.monitor} is a {of} monitor, but the campaign evolves "
                             f"the {self.family} family")
        if self.update not in UPDATE_MODES:
            raise ValueError(f"update must be one of {UPDATE_MODES}, got {self.update!r}")
        if self.n_round < 1 or self.budget_s < 0 or self.seed < 0 or self.max_run_s <= 0:
            raise ValueError(f"need n_round >= 1, budget_s >= 0, seed >= 0: {self}")

    def train_overrides(self) -> dict[str, int]:
        """TrainParams fields of one monitor update."""
        out = {}
        epochs = self.epochs or (FINETUNE_EPOCHS if self.update == "finetune" else None)
        patience = self.patience or (FINETUNE_PATIENCE if self.update == "finetune" else None)
        if epochs:
            out["epochs"] = epochs
        if patience:
            out["patience"] = patience
        return out
