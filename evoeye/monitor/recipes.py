"""Training recipes: the hyper-parameters of a FusionMonitor training, by name.

A recipe is a named `TrainParams`; `train_monitor(recipe=…)` starts from it and applies the
caller's overrides (epochs=…, lr=…). Every figure a recipe produced reproduces with that recipe
by name, so a recipe, once used, is never changed: a better one gets a new name.

* "v1" — random windows in batches of 256, each window encoding its L frames; Adam at a constant
  1e-3; at most 40 epochs, early-stopped after 8 without a better validation AUPRC. Every result
  recorded before recipes had names was made with it.
* "v2" — batches of 1024 windows made of chunks of 32 consecutive windows, so a
  batch's windows share their frames and each frame is encoded once per batch (with L = 5 a
  random batch encodes each window's 5 frames: ≈ 4.4× the encoder work); Adam at 3e-3 held
  for 70 % of 20 epochs, then falling linearly to 0 ("hold-decay"); no early stop (the decay
  is where a noisy plateau settles), the best validation epoch kept. A batch of chunks is
  correlated, so it learns less per epoch than random windows; the higher learning rate and the
  decay make up for it. BENCHMARKS.md has the measurements that chose it, and the paired
  comparison with v1 on RQ1's data.
* "v3" (DEFAULT_RECIPE: `train_monitor`'s, RQ1's, the campaigns' and the studies') — v2's
  FusionMonitor training, unchanged (the same weights; the card names v3); what changed is the
  AEM baseline's part (`evoeye.baselines.aem.AEM_RECIPES`).
* "lookahead-v1" — a monitor for a safety supervisor's trigger (docs/lookahead.md): v3's
  training on the "critical" target (a collision or a critical approach within H, the
  supervisor's own judge of a justified intervention) and a network of its own
  (`RECIPE_NETWORKS`): a context of L = 20 frames (1 s) and the perceived relative kinematics
  (`evoeye.monitor.kinematics`). In the closed loop it warns early enough to act, rarely; its
  frame metrics against Definition 1 are below v3's (docs/lookahead.md has RQ1 with it), so
  v3 stays `train_monitor`'s default and the studies'; `evoeye train` trains lookahead-v1 unless
  told (`COMMAND_RECIPE`).

`keep_parent` is no recipe's choice but a caller's (a campaign's `keep_parent` option): the
weights a training starts from — a fine-tune's (`init_from`) parent — are epoch 0 of its early
stopping, kept unless one of its epochs beats them on the validation split.

Plain data without torch: the command line and the results config read it at start-up.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from evoeye.monitor.threads import MONITOR_THREADS

BATCHINGS = ("windows", "chunks")
SCHEDULES = ("constant", "cosine", "hold-decay")
SELECTIONS = ("auprc", "pauc")  # the early-stopping criterion (evoeye.monitor.lookahead)
NEAR_MISSES = ("safe", "ignored", "unsafe")  # how near misses train (evoeye.monitor.lookahead)
# what a window's label means: a collision within H (Definition 1), or a ground-truth critical
# approach or a collision within H (`evoeye.criticality`; evoeye.monitor.lookahead)
TARGETS = ("collision", "critical")


@dataclass(frozen=True)
class TrainParams:
    """Hyper-parameters of one training run (recorded in the card). The defaults are "v1"."""

    seed: int = 0
    epochs: int = 40  # at most; early stopping usually ends sooner
    patience: int = 8  # epochs without a better validation AUPRC before stopping
    batch_size: int = 256  # windows per optimiser step
    lr: float = 1e-3  # the peak learning rate under a schedule
    weight_decay: float = 1e-5
    grad_clip: float = 1.0
    pos_weight: float | None = None  # None: negatives / positives of the training windows
    threads: int = MONITOR_THREADS  # intra-op threads (evoeye.monitor.threads says why one)
    # -- fields added with the recipes; a card records them only where they differ from v1's
    recipe: str = "v1"  # the recipe these parameters started from
    batching: str = "windows"  # BATCHINGS: random windows, or chunks of consecutive windows
    chunk_windows: int = 1  # consecutive windows per chunk (batching "chunks")
    schedule: str = "constant"  # SCHEDULES: the learning rate over the steps of `epochs`
    warmup_epochs: float = 0.0  # linear warm-up from 0 to `lr`, in epochs
    keep_parent: bool = False  # the starting weights are epoch 0 of early stopping (doc)
    select_on: str = "auprc"  # SELECTIONS: the validation criterion of early stopping
    min_lead_s: float = 0.0  # unsafe windows closer to their collision do not train
    near_misses: str = "safe"  # NEAR_MISSES: the windows of an emergency without a collision
    target: str = "collision"  # TARGETS: what the label of a window means, trained and selected
    # each window's loss times its run's self-normalised, clipped p/q (evoeye.monitor.importance)
    importance_weights: bool = False

    def __post_init__(self) -> None:
        if self.batching not in BATCHINGS:
            raise ValueError(f"unknown batching {self.batching!r}; known: {list(BATCHINGS)}")
        if self.schedule not in SCHEDULES:
            raise ValueError(f"unknown schedule {self.schedule!r}; known: {list(SCHEDULES)}")
        if self.select_on not in SELECTIONS:
            raise ValueError(f"unknown selection {self.select_on!r}; known: {list(SELECTIONS)}")
        if self.near_misses not in NEAR_MISSES:
            raise ValueError(f"unknown near_misses {self.near_misses!r}; known: "
                             f"{list(NEAR_MISSES)}")
        if self.target not in TARGETS:
            raise ValueError(f"unknown target {self.target!r}; known: {list(TARGETS)}")
        if self.min_lead_s < 0:
            raise ValueError(f"min_lead_s must be >= 0, got {self.min_lead_s}")
        for name, least in (("epochs", 1), ("patience", 1), ("batch_size", 1),
                            ("chunk_windows", 1), ("threads", 1)):
            if getattr(self, name) < least:
                raise ValueError(f"{name} must be >= {least}, got {getattr(self, name)}")
        if self.warmup_epochs < 0 or self.lr <= 0:
            raise ValueError(f"need lr > 0 and warmup_epochs >= 0, got {self.lr} and "
                             f"{self.warmup_epochs}")


V1 = TrainParams()
ADDED_FIELDS = ("recipe", "batching", "chunk_windows", "schedule", "warmup_epochs",
                "keep_parent", "select_on", "min_lead_s", "near_misses", "target",
                "importance_weights")
RECIPES: dict[str, TrainParams] = {
    "v1": V1,
    "v2": replace(V1, recipe="v2", batching="chunks", chunk_windows=32, batch_size=1024,
                  lr=3e-3, schedule="hold-decay", epochs=20, patience=20),
}
RECIPES["v3"] = replace(RECIPES["v2"], recipe="v3")  # v2's FusionMonitor; the AEM's part changed
RECIPES["lookahead-v1"] = replace(RECIPES["v3"], recipe="lookahead-v1", target="critical")
# the network a recipe fixes (FusionConfig fields) where the caller gives none; a fine-tune
# keeps its parent's
RECIPE_NETWORKS: dict[str, dict[str, Any]] = {
    "lookahead-v1": {"context_len": 20, "kinematics": True},
}
DEFAULT_RECIPE = "v3"  # train_monitor's, and what RQ1, campaigns and the studies record with
# what `evoeye train` and flows.train train unless told: the monitor a safety supervisor's
# trigger needs (docs/lookahead.md)
COMMAND_RECIPE = "lookahead-v1"
LEGACY_RECIPE = "v1"  # what a record made before recipes had names was trained with


def recipe_params(recipe: str | None = None, **overrides: Any) -> TrainParams:
    """The recipe's TrainParams (default DEFAULT_RECIPE) with `overrides` (TrainParams fields);
    ValueError naming an unknown recipe or field."""
    name = recipe or DEFAULT_RECIPE
    if name not in RECIPES:
        raise ValueError(f"unknown training recipe {name!r}; known: {sorted(RECIPES)}")
    known = {f.name for f in fields(TrainParams)} - {"recipe"}
    if unknown := sorted(set(overrides) - known):
        raise ValueError(f"unknown training parameter(s) {unknown}; known: {sorted(known)}")
    return replace(RECIPES[name], **overrides)


# added for issue 37 (evoeye.monitor.lookahead), after ledger keys recorded every field
LOOKAHEAD_FIELDS = ("select_on", "min_lead_s", "near_misses", "target")
IMPORTANCE_FIELDS = ("importance_weights",)  # added for issue 38 (evoeye.monitor.importance)
LATER_FIELDS = (*LOOKAHEAD_FIELDS, *IMPORTANCE_FIELDS)


def recipe_key(params: TrainParams) -> dict[str, Any]:
    """Every field but the seed, as a ledger key records a training's recipe — the
    LATER_FIELDS only where they differ from their defaults, so keys made before them still
    find their units."""
    return {k: v for k, v in asdict(params).items()
            if k != "seed" and (k not in LATER_FIELDS or v != getattr(V1, k))}


def card_hyperparameters(params: TrainParams) -> dict[str, Any]:
    """The card's record of `params`: every field, but those added with the recipes only where
    they differ from v1's — so a v1 training keeps the card, and the version id, it had."""
    return {k: v for k, v in asdict(params).items()
            if k not in ADDED_FIELDS or v != getattr(V1, k)}
