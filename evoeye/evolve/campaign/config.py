"""What an evolution campaign does: its options, declared once and validated.

`CampaignConfig` is the one declaration of a campaign's options. The command line (`evoeye
evolve`, `evoeye experiment`) and the flows' pydantic parameters (`flows/evolve.py`,
`flows/experiment.py`) are built from its fields (`campaign_options`, with the split flattened
into `split_seed`, `train_frac`, `val_frac`), so an option is added here and nowhere else. Each
field's metadata (`option`) carries its help, its bounds and, where its value must name
something registered, which registry (`known`). This module imports nothing heavy — the command
line reads it at start-up — so the defaults below that come from elsewhere are literals, checked
against their sources by tests/evolve/campaign/test_config.py; validation loads the registries.

Every field but `budget_s` and `reference` enters the campaign id (`campaign_id`), so the same
configuration resumes the same campaign; a field at a value that cannot change what a campaign
does is left out of it, so the campaigns made before the field existed keep their ids.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import operator
import typing
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

from evoeye.seeds import STREAMS_VERSION
from evoeye.splits import SplitSpec

UPDATE_MODES = ("replay", "finetune", "retrain", "warm")  # evoeye.evolve.campaign.loop: each
FEEDBACK_MODES = ("raw", "prior-corrected")  # ŷ as the monitor scores it, or σ(logit − log w)
FINETUNE_EPOCHS, FINETUNE_PATIENCE = 10, 4
REPLAY_EPOCHS, REPLAY_PATIENCE = 2, 1  # per round: passes over the new runs and their replay
REPLAY_RATIO = 1.0  # earlier runs replayed per new run of the round
WARM_EPOCHS, WARM_PATIENCE = 1, 1  # per round: one pass over D_r from G_r's weights
# (these defaults are what a campaign id of update "warm" means, as REPLAY_* and FINETUNE_*
# are for theirs: never change them; other values are `epochs` / `patience` options)
DEFAULT_FAMILY = "fusion"  # evoeye.monitor.families.DEFAULT_FAMILY
DEFAULT_RECIPE, LEGACY_RECIPE = "v3", "v1"  # evoeye.monitor.recipes
DEFAULT_DELTA = 0.2  # evoeye.scenarios.DEFAULT_DELTA
DEFAULT_STRATEGY = "evoeye"  # of `evoeye evolve`, its flow and the nightly deployment
COMMITTEE = 3  # monitors in the committee of the `disagreement` strategy
DEFAULT_HORIZON_S = 3.0  # evoeye.store.windows.DEFAULT_HORIZON_S
MAX_RUN_S = 20.0  # no run lasts longer than this: evoeye.sim.runner.SimConfig().duration_s
SPLIT_OPTIONS = {  # the split's fields as options: SplitSpec field → (option, help)
    "seed": ("split_seed", "Seed of the train/val/test split."),
    "train_frac": ("train_frac", "Train share of round-0 runs."),
    "val_frac": ("val_frac", "Validation share of round-0 runs."),
    "test_batch": ("test_batch", "A round-0 batch held out as the Test Set (its runs are "
                   "always test; default: none)."),
}


def _scenarios() -> Collection[str]:
    from evoeye.scenarios import SCENARIOS

    return SCENARIOS


def _strategies() -> Collection[str]:
    from evoeye.evolve.search import STRATEGIES

    return STRATEGIES


def _committee_strategies() -> Collection[str]:
    from evoeye.evolve.search import READS_DISAGREEMENT

    return READS_DISAGREEMENT


def _families() -> Collection[str]:
    import evoeye.baselines  # noqa: F401  (registers the baseline families: aem, …)
    from evoeye.monitor.families import evolvable_families

    return evolvable_families()


def _methods() -> Collection[str]:
    from evoeye.evolve.campaign.experiment import methods

    return methods()


def _recipes() -> Collection[str]:
    from evoeye.monitor.recipes import RECIPES

    return RECIPES


KNOWN: dict[str, Callable[[], Collection[str]]] = {  # the names a value of each kind may take
    "scenario": _scenarios, "strategy": _strategies, "update": lambda: UPDATE_MODES,
    "feedback": lambda: FEEDBACK_MODES, "family": _families, "method": _methods,
    "recipe": _recipes,
}


def known(kind: str) -> Collection[str]:
    """The names a value of `kind` (a key of KNOWN) may take, from their registries."""
    return KNOWN[kind]()


def check_known(kind: str, values: Collection[str]) -> None:
    """ValueError naming the values of `kind` that are unknown (or that there is no value)."""
    names = known(kind)
    unknown = [v for v in values if v not in names]
    if unknown or not values:
        raise ValueError(f"unknown {kind} {unknown}; known: {sorted(names)}")


def option(default: Any = dataclasses.MISSING, help: str = "", *,  # noqa: A002 (as typer's)
           factory: Callable[[], Any] | None = None, ge: float | None = None,
           gt: float | None = None, le: float | None = None, names: str | None = None,
           internal: bool = False) -> Any:
    """A CampaignConfig field with what the command line and the flows show and check:
    its help, bounds (ge / gt / le), the registry its value names (a KNOWN key), and whether it
    is `internal` (not an option: set by the code, never by a user)."""
    meta = {"help": help, "ge": ge, "gt": gt, "le": le, "names": names, "internal": internal}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class CampaignConfig:
    """What a campaign does. Every field but `budget_s` and `reference` is part of its id."""

    scenario: str = option("highway-cut-in", "Logical scenario.", names="scenario")
    strategy: str = option(DEFAULT_STRATEGY, "Acquisition strategy.", names="strategy")
    budget_s: float = option(600.0, "Simulated seconds the acquired runs may use in total.",
                             ge=0.0)
    seed: int = option(0, "Campaign seed: the proposals and the runs' seeds.", ge=0)
    monitor: str | None = option(None, "G_0 (default: the newest monitor of the family "
                                 "trained from scratch on the scenario, or its initial "
                                 "version).")
    n_round: int = option(20, "Runs per round (N_round).", ge=1)
    update: str = option("retrain", "Monitor update per round: retrain (from scratch on every "
                         "record), warm (G_r on every record, one epoch), replay (fine-tune "
                         "G_r on the round's runs and as many earlier ones) or finetune (G_r on "
                         "every record, up to 10 epochs).", names="update")
    epochs: int | None = option(None, "Epochs per monitor update (default: 2 with replay, 1 "
                                "warm, 10 fine-tuning, the trainer's when retraining).", ge=1)
    patience: int | None = option(None, "Early-stopping patience per update (default: 1 with "
                                  "replay, 1 warm, 4 fine-tuning, the trainer's when "
                                  "retraining).", ge=1)
    delta: float = option(DEFAULT_DELTA, "Neighbourhood radius δ of the density-aware "
                          "strategies, a share of each parameter's range.", gt=0.0, le=1.0)
    feedback: str = option("raw", "ŷ in f_r = mean |ŷ − y|: raw monitor scores, or "
                           "prior-corrected (undo the training pos_weight; see "
                           "evoeye.evolve.search.feedback).", names="feedback")
    family: str = option(DEFAULT_FAMILY, "The monitor family evolved: fusion, or another "
                         "evolvable one, e.g. aem (AEM-Evo; judged on the FusionMonitor's Hard "
                         "Set).", names="family")
    reference: str | None = option(None, "Another family than fusion: the FusionMonitor G_0 "
                                   "whose Hard Set judges (default: the newest).")
    keep_parent: bool = option(False, "A fine-tuned update (warm, replay, finetune) keeps G_r "
                               "unless one of its epochs beats G_r on the validation split (off: "
                               "Algorithm 1's update, which always replaces it).")
    committee: int = option(COMMITTEE, "Monitors whose disagreement the `disagreement` "
                            "strategy reads: G_r and committee − 1 companions trained beside "
                            "it (each round costs as many monitor updates).", ge=2)
    importance_weights: bool = option(False, "Train every monitor update with each run's "
                                      "self-normalised, clipped weight p/q (exact for runs "
                                      "of an importance-sampling strategy such as ce-is, 1 "
                                      "for runs drawn from the scenario distribution).")
    recipe: str = option(DEFAULT_RECIPE, "Training recipe of the monitor updates (and of a G_0 "
                         "the campaign trains itself): v1 (every campaign before recipes had "
                         "names), v2, or v3 (v2's FusionMonitor training, a faster AEM).",
                         names="recipe")
    horizon_s: float = option(DEFAULT_HORIZON_S, "Label horizon H, s.", gt=0.0)
    splits: SplitSpec = option(factory=SplitSpec, help="The train/val/test split.")
    max_run_s: float = option(MAX_RUN_S, "No run lasts longer, s (the simulator's duration).",
                              gt=0.0, internal=True)

    def __post_init__(self) -> None:
        for f in fields(self):
            value, meta = getattr(self, f.name), f.metadata
            if value is None or isinstance(value, SplitSpec):
                continue
            if meta["names"]:
                names = known(meta["names"])
                if value not in names:
                    raise ValueError(f"unknown {f.name} {value!r}; known: {sorted(names)}")
            _check_bounds(f.name, value, meta)
        if self.family != DEFAULT_FAMILY and self.strategy in _committee_strategies():
            raise ValueError(f"the {self.strategy} strategy's committee is of FusionMonitors: "
                             f"it cannot evolve the {self.family} family")
        if self.importance_weights and self.family != DEFAULT_FAMILY:
            raise ValueError(f"importance weights train FusionMonitors: the {self.family} "
                             "family has no weighted training")
        if self.monitor:
            from evoeye.monitor.families import family_of

            if (of := family_of(self.monitor).name) != self.family:
                raise ValueError(f"G_0 {self.monitor} is a {of} monitor, but the campaign "
                                 f"evolves the {self.family} family")

    def train_overrides(self) -> dict[str, int | bool]:
        """TrainParams fields of one monitor update."""
        out = {}
        default = {"finetune": (FINETUNE_EPOCHS, FINETUNE_PATIENCE),
                   "replay": (REPLAY_EPOCHS, REPLAY_PATIENCE),
                   "warm": (WARM_EPOCHS, WARM_PATIENCE)}.get(self.update, (None, None))
        epochs, patience = self.epochs or default[0], self.patience or default[1]
        if epochs:
            out["epochs"] = epochs
        if patience:
            out["patience"] = patience
        if self.keep_parent and self.update != "retrain":
            out["keep_parent"] = True
        if self.importance_weights:
            out["importance_weights"] = True
        return out


def campaign_id(config: CampaignConfig, g0: str, initial_ids: Sequence[str], *,
                feedback_blind: bool, committee: bool) -> str:
    """`evo-[<family>-]<strategy>-s<seed>-<hash>` of every field but the budget and the
    reference, with G_0 and D_init's runs: same inputs, same id. `feedback_blind`: the strategy
    never reads the feedback; `committee`: it reads a committee's disagreement."""
    cfg = dataclasses.asdict(config)
    cfg.pop("budget_s")
    cfg.pop("reference")
    # raw: the original loop, whose campaigns keep their ids; a feedback-blind strategy
    # acquires the same runs and trains the same monitors under either mode
    if cfg["feedback"] == "raw" or feedback_blind:
        cfg.pop("feedback")
    if cfg["family"] == DEFAULT_FAMILY:  # likewise
        cfg.pop("family")
    if not committee:  # only a strategy that reads the disagreement trains a committee
        cfg.pop("committee")
    if not cfg["keep_parent"]:  # Algorithm 1's update, every campaign's before the option
        cfg.pop("keep_parent")
    if not cfg["importance_weights"]:  # likewise: unweighted training
        cfg.pop("importance_weights")
    if cfg["recipe"] == LEGACY_RECIPE:  # the recipe every campaign before it trained by
        cfg.pop("recipe")
    cfg["monitor"] = g0
    cfg["streams"] = STREAMS_VERSION  # its seed streams (`evoeye.seeds`)
    cfg["initial"] = hashlib.sha256("\n".join(initial_ids).encode()).hexdigest()
    digest = hashlib.sha256(json.dumps(cfg, sort_keys=True).encode()).hexdigest()[:10]
    family = "" if config.family == DEFAULT_FAMILY else f"{config.family}-"
    return f"evo-{family}{config.strategy}-s{config.seed}-{digest}"


def _check_bounds(name: str, value: float, meta: Mapping[str, Any]) -> None:
    for bound, holds, word in (("ge", operator.ge, ">="), ("gt", operator.gt, ">"),
                               ("le", operator.le, "<=")):
        if meta[bound] is not None and not holds(value, meta[bound]):
            raise ValueError(f"{name} must be {word} {meta[bound]}, got {value}")


@dataclass(frozen=True)
class Option:
    """One campaign option as the command line and the flows show it (`campaign_options`)."""

    name: str  # flat: budget_s, split_seed, …
    type: type  # int, float or str
    optional: bool  # None is a value (the default decides)
    default: Any
    help: str
    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    names: str | None = None  # a KNOWN key


def campaign_options(exclude: Collection[str] = ()) -> list[Option]:
    """CampaignConfig's options, in field order, the split flattened; minus `exclude` (flat
    names) and the internal fields."""
    hints = typing.get_type_hints(CampaignConfig)
    out = []
    for f in fields(CampaignConfig):
        if f.metadata["internal"]:
            continue
        if hints[f.name] is SplitSpec:
            split = {s.name: s for s in fields(SplitSpec)}
            split_hints = typing.get_type_hints(SplitSpec)
            bounds = {"train_frac": {"ge": 0.0, "le": 1.0}, "val_frac": {"ge": 0.0, "le": 1.0}}
            out += [Option(name, *_kind(split_hints[key]), split[key].default, text,
                           **bounds.get(key, {})) for key, (name, text) in SPLIT_OPTIONS.items()]
            continue
        m = f.metadata
        out.append(Option(f.name, *_kind(hints[f.name]), f.default, m["help"], m["ge"],
                          m["gt"], m["le"], m["names"]))
    return [o for o in out if o.name not in exclude]


def _kind(hint: Any) -> tuple[type, bool]:
    """(type, optional) of a field's annotation: `str | None` → (str, True)."""
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    return (args[0], True) if args else (hint, False)


def config_from(values: Mapping[str, Any], **fixed: Any) -> CampaignConfig:
    """The CampaignConfig of flat option values (`campaign_options`' names; absent ones keep
    their defaults) and `fixed` fields."""
    flat = {**values, **fixed}
    given = {k: v for k, v in flat.items() if k in {f.name for f in fields(CampaignConfig)}}
    split = {key: flat[name] for key, (name, _) in SPLIT_OPTIONS.items() if name in flat}
    if split and "splits" not in given:
        given["splits"] = SplitSpec(**split)
    return CampaignConfig(**given)


def option_values(config: CampaignConfig, exclude: Collection[str] = ()) -> dict[str, Any]:
    """The flat option values of `config` (the inverse of `config_from`); ValueError if an
    internal field is not at its default (no option could carry it)."""
    default = CampaignConfig(config.scenario)
    for f in fields(CampaignConfig):
        if f.metadata["internal"] and getattr(config, f.name) != getattr(default, f.name):
            raise ValueError(f"{f.name} is no campaign option: it must keep its default")
    out = {k: v for k, v in dataclasses.asdict(config).items() if k != "splits"}
    out.update({name: getattr(config.splits, key) for key, (name, _) in SPLIT_OPTIONS.items()})
    return {o.name: out[o.name] for o in campaign_options(exclude)}
