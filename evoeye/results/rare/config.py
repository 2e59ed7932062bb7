"""What the testing-efficiency protocol runs, at what size: declared once and validated.

Plain data (the command line reads it at start-up). The protocol (`runner.py`):

* Regimes: a logical scenario and the ADS profile that drives it (`scenario:profile`), chosen
  where failures are rare — `highway-cut-in:cautious` (≈ 1 % of uniform runs: 11 of 1 000 on
  the screening seed) and `highway-cut-in:defensive` (≈ 0.1 %: 1 of 2 000).
* Generative mode only: every strategy simulates its own runs, `runs` per seed, in batches of
  `batch` (a strategy adapts between batches). No initial set: ce-is's first batch is drawn
  from p itself, and a curve that finds no failure is part of the result.
* Seeds are paired across strategies (the same seed, a different run-seed stream per strategy),
  and every run seed derives from `data_seed`, which no earlier study used.
* Every collision found is classified (`evoeye.evaluation.mechanism`: the partner's motion) and,
  with `explain`, attributed (`evoeye explain`'s counterfactuals: the module whose oracle
  prevents it); a distinct mechanism is one (class, root cause) pair.
* With `learn` (`LearnConfig`), the learning side: a monitor trained from scratch on each
  curve's first n runs (importance-weighted by their p/q), judged on a uniform Test Set of its
  own seed sized to hold ≥ 50 failures (`learn.py`). 4 000 runs at ≈ 1.4 % hold ≈ 56.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

from evoeye.results.efficiency.config import MAX_MEMBERS, RECIPES, dataclass_from, parse_regime

REFERENCE = "uniform"
STRATEGIES = (REFERENCE, "ce-is")
# the strategies that need no monitor (the protocol trains none): the others read feedback
USABLE = (REFERENCE, "ce-is", "subset", "subset-deep", "subset-spread", "sobol", "avfuzzer")
# the strategies that estimate the failure rate under p: from their runs' exact p/q (Uniform:
# 1; ce-is), or, for subset simulation, from its levels (`evoeye.evolve.search.subset`; not
# subset-deep's one-step levels, whose estimate a noisy level biases, nor subset-spread's)
ESTIMATING = (REFERENCE, "ce-is", "subset")
# the strategies whose runs carry their exact p/q (Uniform: 1): the ones an importance-weighted
# monitor can be trained on (the learning side trains the others unweighted)
WEIGHTED = (REFERENCE, "ce-is")
REGIMES = ("highway-cut-in:cautious", "highway-cut-in:defensive")
# LearnConfig's, absent at their default
LEARN_LATER_FIELDS = ("test_max_runs", "controls", "strategies")
UNWEIGHTED = "-unweighted"  # a control's name: a weighted strategy's runs trained unweighted


@dataclass(frozen=True)
class LearnConfig:
    """What the learning side trains and judges on (`learn.py`; module doc)."""

    budgets: tuple[int, ...] = (50, 100, 200)  # a curve's first n runs, log-spaced
    test_runs: int = 4000  # ≈ 56 collisions at the ≈ 1.4 % regime
    val_runs: int = 200
    val_collisions: int = 20
    members: int = 1  # 3 did not narrow Uniform's spread at 80 runs (efficiency.md), at 3×
    recipe: str = "v3"
    horizon_s: float = 3.0
    context_len: int = 5
    min_test_failures: int = 50  # a Test Set with fewer cannot judge the regime (issue 38)
    # where test_runs hold fewer, the Test stream drawn on to this many runs at most, outcome
    # first, and the set weighted back (`testset.py`); 0: the test_runs batch alone
    test_max_runs: int = 0
    # weighted strategies whose runs also train unweighted, beside (`<name>-unweighted`): the
    # control for what the weights themselves add
    controls: tuple[str, ...] = ()
    # the strategies whose curves are learned from, Uniform's always (empty: every one). The
    # other curves are still simulated and reported on the testing side
    strategies: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name in ("budgets", "controls", "strategies"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        b = self.budgets
        if len(b) < 2 or list(b) != sorted(set(b)) or b[0] < 1:
            raise ValueError(f"budgets must be at least two increasing run counts, got {b}")
        for name in ("test_runs", "val_runs", "context_len", "min_test_failures"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.test_max_runs and self.test_max_runs <= self.test_runs:
            raise ValueError(f"test_max_runs ({self.test_max_runs}) must exceed test_runs "
                             f"({self.test_runs}), or be 0 (no further Test runs)")
        if self.val_collisions < 0:
            raise ValueError(f"val_collisions must be >= 0, got {self.val_collisions}")
        if not 1 <= self.members <= MAX_MEMBERS:
            raise ValueError(f"members must be 1 to {MAX_MEMBERS}, got {self.members}")
        if self.recipe not in RECIPES:
            raise ValueError(f"unknown training recipe {self.recipe!r}; known: {list(RECIPES)}")
        if not self.horizon_s > 0:
            raise ValueError(f"horizon_s must be > 0, got {self.horizon_s}")

    def check_runs(self, runs: int) -> None:
        """ValueError if a budget exceeds the curves' `runs`."""
        if self.budgets[-1] > runs:
            raise ValueError(f"the largest budget ({self.budgets[-1]}) exceeds the runs a "
                             f"curve holds ({runs})")

    def to_dict(self) -> dict:
        """Every field, but those added later only where set (LEARN_LATER_FIELDS: the configs
        recorded before them, and their ledger keys, stay as they were)."""
        return {f.name: list(v) if isinstance(v, tuple) else v
                for f in fields(self) if (v := getattr(self, f.name)) is not None
                and not (f.name in LEARN_LATER_FIELDS and v == getattr(LearnConfig(), f.name))}

    def curve_key(self) -> dict:
        """What fixes how one curve is learned (a learned curve's ledger key): every field but
        `controls` and `strategies`, which choose the curves and change none."""
        return {k: v for k, v in self.to_dict().items() if k not in ("controls", "strategies")}

    def learns(self, strategy: str) -> bool:
        """Whether `strategy`'s curves are learned from (`strategies`; Uniform's always)."""
        return not self.strategies or strategy in (REFERENCE, *self.strategies)

    @classmethod
    def from_dict(cls, data: Mapping) -> LearnConfig:
        return dataclass_from(cls, data, "learning")


@dataclass(frozen=True)
class RareConfig:
    """Everything the protocol regenerates, and at what size (module doc)."""

    regimes: tuple[str, ...] = REGIMES
    strategies: tuple[str, ...] = STRATEGIES
    seeds: tuple[int, ...] = tuple(range(40))  # paired across strategies
    runs: int = 200  # simulated per seed and strategy
    batch: int = 10  # runs between two adaptations of a strategy
    data_seed: int = 9_100  # the run seeds' stream (fresh: no earlier study drew from it)
    explain: bool = True  # attribute every collision found to a module (counterfactuals)
    # ce-is's elite share and screening z, chosen on screening seeds of data_seed 9_000
    ce_rho: float = 0.2
    ce_screen_z: float = 2.0
    # the learning side (`learn.py`): its LearnConfig as a mapping (stored whole, defaults
    # filled in), or None where it is not run (every recorded protocol); its curves are the
    # ones above
    learn: Mapping | None = None

    def __post_init__(self) -> None:
        for name in ("regimes", "strategies", "seeds"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for regime in self.regimes:
            parse_regime(regime)
        if not self.regimes:
            raise ValueError("need at least one regime")
        if REFERENCE not in self.strategies or len(set(self.strategies)) != len(self.strategies):
            raise ValueError(f"the strategies must be distinct and include {REFERENCE!r}, "
                             f"got {self.strategies}")
        if unusable := [s for s in self.strategies if s not in USABLE]:
            raise ValueError(f"strategies {unusable} need a monitor; the rare-failure protocol "
                             f"runs {', '.join(USABLE)}")
        if len(self.seeds) < 2 or len(set(self.seeds)) != len(self.seeds) or min(self.seeds) < 0:
            raise ValueError(f"need at least 2 distinct seeds >= 0, got {self.seeds}")
        if self.batch < 1 or self.runs < self.batch or self.runs % self.batch:
            raise ValueError(f"runs must be whole batches (runs {self.runs}, batch {self.batch})")
        if not (0.0 < self.ce_rho < 1.0 and self.ce_screen_z >= 0.0):
            raise ValueError(f"ce-is needs 0 < ce_rho < 1 and ce_screen_z >= 0, got "
                             f"{self.ce_rho}, {self.ce_screen_z}")
        if self.data_seed < 0:
            raise ValueError(f"data_seed must be >= 0, got {self.data_seed}")
        if self.learn is not None:
            learning = LearnConfig.from_dict(self.learn)
            learning.check_runs(self.runs)
            if bad := [s for s in learning.strategies if s not in self.strategies]:
                raise ValueError(f"learning strategies {bad} are not among the protocol's "
                                 f"strategies {list(self.strategies)}")
            able = [s for s in self.strategies if s in WEIGHTED and s != REFERENCE
                    and learning.learns(s)]
            if bad := [c for c in learning.controls if c not in able]:
                raise ValueError(f"learning controls {bad}: a control trains a weighted "
                                 f"strategy's runs unweighted; pick from {able}")
            object.__setattr__(self, "learn", learning.to_dict())

    @property
    def learning(self) -> LearnConfig | None:
        """The learning side's config, or None where it is not run."""
        return None if self.learn is None else LearnConfig.from_dict(self.learn)

    def check_names(self) -> None:
        """ValueError naming a scenario or ADS profile no registry knows (loads them)."""
        from evoeye.ads.profiles import ADS_PROFILES
        from evoeye.scenarios import SCENARIOS

        for regime in self.regimes:
            scenario, profile = parse_regime(regime)
            if scenario not in SCENARIOS or profile not in ADS_PROFILES:
                raise ValueError(f"regime {regime!r}: scenarios are {sorted(SCENARIOS)}, ADS "
                                 f"profiles {sorted(ADS_PROFILES)}")

    def options(self, strategy: str) -> dict:
        """The options strategy `strategy`'s factory takes from this config (loads it)."""
        from evoeye.evolve.search.registry import strategy_options

        return strategy_options(strategy, batch=self.batch, rho=self.ce_rho,
                                screen_z=self.ce_screen_z)

    def unit(self, regime: str, strategy: str, seed: int) -> dict:
        """The inputs that fix one curve's runs (its ledger key)."""
        return {"regime": regime, "strategy": strategy, "seed": seed, "runs": self.runs,
                "options": self.options(strategy), "data_seed": self.data_seed,
                "explain": self.explain}

    def to_dict(self) -> dict:
        return {f.name: list(v) if isinstance(v, tuple) else v
                for f in fields(self) if (v := getattr(self, f.name)) is not None}

    def changed(self) -> dict:
        """The fields that differ from the defaults, as JSON values."""
        default = RareConfig()
        return {k: v for k, v in self.to_dict().items() if v != default.to_dict().get(k)}

    @classmethod
    def from_dict(cls, data: Mapping) -> RareConfig:
        return dataclass_from(cls, data, "rare-failure")
