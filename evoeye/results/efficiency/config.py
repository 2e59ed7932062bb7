"""What the sample-efficiency study runs, at what size: declared once and validated.

Plain data (the command line reads it at start-up). Sizes, and why:

* Regimes: a logical scenario and the ADS profile that drives it (`scenario` or
  `scenario:profile`), by default each registered scenario under each of its `ads_profiles`.
  Collisions are common under the default stack (≈ 25 % / 55 % of uniform
  runs); where they are rare (2–10 %), Uniform spends most of its budget on runs with nothing
  to learn. The cautious stack at the intersection is that regime (9 of 200 uniform runs
  collided, 4.5 %, on the seed the profiles were chosen on; the cautious stack on the highway
  collided in 2 of 200, too rare to learn from; the firm-yield stack at the intersection in
  21 of 200, at the band's edge).
* The pool: every screened strategy picks from the same pre-simulated uniform runs (5 000), so
  strategies differ only in their choices and the oracle can look ahead.
* The Test Set (1 000 uniform runs, its own seed) and the boundary set (pairs of a safe and a
  colliding uniform run, bisected in θ under one run seed) are built once, by no strategy and no
  monitor; the validation set (200 runs) early-stops and calibrates every monitor alike, and is
  charged to no strategy's budget.
* Learning curves start from 40 initial runs drawn from the pool (the same for every strategy
  at a seed) and are measured at log-spaced budgets ×2, ×4, ×8 (80, 160, 320 runs, initial runs
  included); Uniform goes on to ×16 so that the budget it needs to match a strategy can be read
  off its own curve up to a factor of 2.
* Acquisition comes in rounds of 20 runs, after each of which the per-round monitor the
  strategies' feedback comes from is updated: by the replay fine-tune (`update="replay"`, the
  paper's loop, `evoeye evolve --update replay`) or trained again from scratch on every run so
  far (`update="retrain"`, what `evoeye evolve` does by default; only for the strategies that
  read feedback — for the others nothing reads it, and the deployed monitor at a checkpoint is
  the checkpoint's from-scratch one).
  At a checkpoint the monitor is trained from scratch on everything acquired, with the training
  seed of that seed and checkpoint shared by every strategy (the pairing absorbs it).
* `members`: the checkpoint's monitor is an ensemble of that many from-scratch members (member
  0 with the checkpoint's training seed, the others with seeds derived from it:
  `evoeye.monitor.ensemble.member_seeds`), scored by their mean risk and calibrated on the
  validation set like one monitor. A single monitor's Test AUPRC varies from training seed to
  training seed more than the strategies differ; k members vary less, at k times the cost.
  The per-round monitor the strategies' feedback comes from (and `disagreement`'s committee)
  stays one network.
* `val_collisions`: the validation set holds at least that many colliding runs. The uniform
  validation batch stays as it is; its seed stream is drawn on (`data.extend_validation`)
  until enough further runs collided, and their unsafe windows (only those) join it. The
  validation negatives are then exactly the uniform batch's, so the thresholds calibrated for a
  target FPR (a share of negative frames) do not move; early stopping sees more positives.
* The oracle (a lower bound, `oracle.py`) tries `oracle_candidates` increments per step, a step
  from one checkpoint to the next (`oracle_step="checkpoint"`, as every recorded study ran it)
  or every round (`"round"`); its controls choose among uniform draws (`oracle-uniform`) or
  among training seeds on Uniform's runs (`oracle-seeds`).
* `qbc` (`qbc.py`) is a study-only diagnostic, in pool mode only: query-by-committee on the
  unused pool runs' own windows, which generative mode does not have.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields

from evoeye.scenarios import SCENARIO_SPECS

MODES = ("pool", "generative")
UPDATES = ("replay", "retrain")  # the per-round monitor's update rule
STRATEGIES = ("uniform", "sobol", "boundary", "disagreement", "evoeye-knn", "evoeye")
REFERENCE = "uniform"
ORACLE = "oracle"
ORACLE_UNIFORM = "oracle-uniform"  # the oracle's control: it chooses among uniform draws only
ORACLE_SEEDS = "oracle-seeds"  # its other control: Uniform's runs, the best of k training seeds
CONTROLS = (ORACLE_UNIFORM, ORACLE_SEEDS)
CEILINGS = (ORACLE, *CONTROLS)  # curves that know outcomes: no strategy, no update rule
ORACLE_STEPS = ("checkpoint", "round")  # the oracle chooses once per checkpoint, or per round
QBC = "qbc"  # query-by-committee on the unused pool runs' own windows (pool mode only)
DIAGNOSTICS = (QBC,)  # study-only strategies: no registry entry, no per-round monitor
NO_UPDATE = (*CEILINGS, *DIAGNOSTICS)  # curves without the per-round (update) monitor
DEFAULT_PROFILE = "default"  # evoeye.ads.profiles.DEFAULT_PROFILE
# evoeye.monitor.recipes (importing it loads torch)
RECIPES, DEFAULT_RECIPE = ("v1", "v2", "v3", "lookahead-v1"), "v3"
ORACLE_MIN_CANDIDATES = 4  # oracle.py: the error, margin and mixed increments, and a uniform one
MAX_MEMBERS = 8  # evoeye.monitor.ensemble.MAX_MEMBERS (importing it loads torch)
# fields added since studies were recorded: left out of `to_dict` at their defaults, so a
# study that does not use them stores the config it always did
LATER_FIELDS = ("members", "val_collisions", "oracle_step")


def dataclass_from(cls, data: Mapping, noun: str):
    """`cls(**data)` for a frozen config dataclass, with a ValueError naming the config (`noun`)
    when `data` is not a mapping or holds a key no field has."""
    if not isinstance(data, Mapping):
        raise ValueError(f"the {noun} config must be a mapping, got {data!r}")
    if unknown := sorted(set(data) - {f.name for f in fields(cls)}):
        raise ValueError(f"unknown {noun} config key(s) {unknown}")
    return cls(**data)


def parse_regime(regime: str) -> tuple[str, str]:
    """"scenario" or "scenario:profile" → (scenario, profile)."""
    scenario, _, profile = regime.partition(":")
    if not scenario or ":" in profile:
        raise ValueError(f"a regime is SCENARIO or SCENARIO:PROFILE, got {regime!r}")
    return scenario, profile or DEFAULT_PROFILE


def regime_name(scenario: str, profile: str) -> str:
    """The regime's name: the scenario, and the profile unless it is the default."""
    return scenario if profile == DEFAULT_PROFILE else f"{scenario}:{profile}"


@dataclass(frozen=True)
class EfficiencyConfig:
    """Everything the study regenerates, and at what size (module doc)."""

    # every registered scenario under each ADS profile it is studied with (its
    # `ScenarioSpec.ads_profiles`): the intersection's cautious stack is the rare-failure one
    regimes: tuple[str, ...] = field(default_factory=lambda: tuple(
        regime_name(name, profile) for name, spec in SCENARIO_SPECS.items()
        for profile in spec.ads_profiles))
    mode: str = "pool"  # pool: pick from the pre-simulated pool; generative: simulate
    update: str = "replay"  # the per-round monitor: fine-tuned (replay) or trained again
    strategies: tuple[str, ...] = STRATEGIES
    seeds: tuple[int, ...] = tuple(range(10))  # campaign seeds, paired across strategies
    oracle: bool = True  # the greedy oracle (a lower bound), its uniform-only control (pool)
    oracle_candidates: int = 6  # increments (the seeds control: training seeds) per step
    initial_runs: int = 40
    checkpoints: tuple[int, ...] = (80, 160, 320)  # total runs, initial runs included
    reference_checkpoints: tuple[int, ...] = (640,)  # Uniform's further ones
    n_round: int = 20
    pool_runs: int = 5000
    test_runs: int = 1000
    val_runs: int = 200
    oracle_runs: int = 500  # the set the oracle judges its candidates on (not the Test Set)
    boundary_pairs: int = 150
    boundary_steps: int = 4  # bisections per pair: the final bracket is 1/16 of the pair
    data_seed: int = 7_000  # pool; +1 test, +2 val, +3 oracle, +4 the boundary set's sources
    horizon_s: float = 3.0
    recipe: str = DEFAULT_RECIPE  # the training recipe of every monitor of the study
    epochs: int | None = None  # every training (None: the recipe's)
    patience: int | None = None
    # every monitor trained with its runs' p/q (exact for ce-is's runs, 1 for the others)
    importance_weights: bool = False
    members: int = 1  # from-scratch members of each checkpoint's monitor (module doc)
    val_collisions: int = 0  # colliding runs the validation set holds at least (module doc)
    oracle_step: str = "checkpoint"  # the oracle steps from checkpoint to checkpoint, or rounds

    @property
    def train_overrides(self) -> dict[str, int | bool]:
        """TrainParams fields every monitor of the study gets."""
        out: dict[str, int | bool] = {
            k: v for k, v in (("epochs", self.epochs), ("patience", self.patience))
            if v is not None}
        if self.importance_weights:
            out["importance_weights"] = True
        return out

    def __post_init__(self) -> None:
        for name in ("regimes", "strategies", "seeds", "checkpoints", "reference_checkpoints"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for regime in self.regimes:
            parse_regime(regime)
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {self.mode!r}")
        if self.update not in UPDATES:
            raise ValueError(f"update must be one of {UPDATES}, got {self.update!r}")
        if self.oracle_step not in ORACLE_STEPS:
            raise ValueError(f"oracle_step must be one of {ORACLE_STEPS}, got "
                             f"{self.oracle_step!r}")
        if self.mode != "pool" and (pool_only := [s for s in self.strategies
                                                  if s in DIAGNOSTICS]):
            raise ValueError(f"{', '.join(pool_only)} is a pool-mode diagnostic (it scores the "
                             f"unused pool runs' own windows): drop it or use mode 'pool'")
        if self.recipe not in RECIPES:
            raise ValueError(f"unknown training recipe {self.recipe!r}; known: {list(RECIPES)}")
        if REFERENCE not in self.strategies:
            raise ValueError(f"the strategies must include the reference {REFERENCE!r}")
        if len(self.seeds) < 2 or len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"need at least 2 distinct seeds, got {self.seeds}")
        points = (self.initial_runs, *self.checkpoints, *self.reference_checkpoints)
        if list(points) != sorted(set(points)) or self.initial_runs < 2:
            raise ValueError(f"initial runs and checkpoints must increase, got {points}")
        if any((c - self.initial_runs) % self.n_round for c in points[1:]):
            raise ValueError(f"every checkpoint must be the initial runs plus whole rounds of "
                             f"{self.n_round}, got {points}")
        for name in ("pool_runs", "test_runs", "val_runs", "oracle_runs", "boundary_pairs",
                     "boundary_steps", "n_round"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.oracle_candidates < ORACLE_MIN_CANDIDATES:  # else the oracle tries more than
            raise ValueError(  # its controls, which try exactly this many
                f"oracle_candidates must be >= {ORACLE_MIN_CANDIDATES} (the oracle's three "
                f"targeted increments and a uniform one), got {self.oracle_candidates}")
        if not 1 <= self.members <= MAX_MEMBERS:
            raise ValueError(f"members must be 1 to {MAX_MEMBERS}, got {self.members}")
        if self.val_collisions < 0:
            raise ValueError(f"val_collisions must be >= 0, got {self.val_collisions}")
        if self.pool_runs < self.initial_runs + points[-1]:
            raise ValueError(f"the pool ({self.pool_runs}) must hold the initial runs and the "
                             f"largest budget ({points[-1]})")

    def check_names(self) -> None:
        """ValueError naming a scenario, ADS profile or strategy no registry knows (loads the
        registries)."""
        from evoeye.ads.profiles import ADS_PROFILES
        from evoeye.evolve.search import GENERATIVE_ONLY
        from evoeye.evolve.search import STRATEGIES as KNOWN
        from evoeye.scenarios import SCENARIOS

        for regime in self.regimes:
            scenario, profile = parse_regime(regime)
            if scenario not in SCENARIOS or profile not in ADS_PROFILES:
                raise ValueError(f"regime {regime!r}: scenarios are {sorted(SCENARIOS)}, ADS "
                                 f"profiles {sorted(ADS_PROFILES)}")
        if unknown := [s for s in self.strategies if s not in KNOWN and s not in DIAGNOSTICS]:
            raise ValueError(f"unknown strategy {unknown}; known: "
                             f"{sorted([*KNOWN, *DIAGNOSTICS])}")
        if self.mode == "pool" and (only := sorted(GENERATIVE_ONLY & set(self.strategies))):
            raise ValueError(f"strategies {only} propose new points only: run them with "
                             "--mode generative")

    @property
    def budgets(self) -> tuple[int, ...]:
        """Every checkpoint any strategy reaches (the reference's included)."""
        return (*self.checkpoints, *self.reference_checkpoints)

    def checkpoints_of(self, strategy: str) -> tuple[int, ...]:
        return self.budgets if strategy == REFERENCE else self.checkpoints

    def to_dict(self) -> dict:
        """Every field, but the LATER_FIELDS only where they differ from their defaults."""
        default = EfficiencyConfig()
        return {f.name: v for f in fields(self) if (v := getattr(self, f.name)) !=
                getattr(default, f.name) or f.name not in LATER_FIELDS}

    def changed(self) -> dict:
        """The fields that differ from the defaults, as JSON values (lists for tuples)."""
        default = EfficiencyConfig()
        return {f.name: list(v) if isinstance(v, tuple) else v for f in fields(self)
                if (v := getattr(self, f.name)) != getattr(default, f.name)}

    @classmethod
    def from_dict(cls, data: Mapping) -> EfficiencyConfig:
        return dataclass_from(cls, data, "efficiency")
