"""What `evoeye results` runs: its sizes and choices, declared once and validated.

Plain data that imports nothing heavy (the command line reads it at start-up); the defaults that
come from elsewhere are literals checked against their sources by tests/results/test_config.py;
the scenarios and baselines are read from their registries.

Sizes, and why:

* Training seeds (RQ1, the monitor ablation; the first k are RQ2's re-seeded G_0s): 6.
  At least 5 are wanted, but 5 pairs can never give a Wilcoxon p below 2 / 2^5 = 0.0625;
  6 can reach 0.031.
* Campaign seeds (RQ2 and the evolution ablations, paired across methods): 20, inside the 16–25
  pairs estimated for a 5-F1-point difference at 80 % power (the report prints the
  pairs each comparison's measured SDs and pair correlation call for).
* Final seeds: each campaign's final monitor is judged by the mean over k = 3 training seeds of
  its last update (module doc of `evoeye.results.rq2`).
* Test Set: a batch of 400 runs simulated apart at its own seed, at least 3× the paper's test
  runs (75 on S1, 132 on S2); with it, the initial runs split train : val = 0.8 : 0.2 (the
  paper's 6 h : 1.5 h), so the Test Set is that batch alone.
* RQ1's data: RQ1 and the monitor ablation train on at least 1300 initial runs per scenario
  (1040 train : 260 val), on a data root of their own when the study simulates fewer
  (`evoeye.results.study.monitor_study`); RQ2 keeps the study's, its D_init. The
  FusionMonitor learns S1's rare failures (cut-ins, early collisions) only from enough of them:
  on a development seed its test AUPRC went 41 → 55 → 56 → 70 → 72 with 107, 209, 418, 836
  and 1040 training runs (TTC-2D: 53), while RQ2 needs a small D_init for evolution to add to
  and campaigns whose cost grows with it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from evoeye.evaluation.baselines import BASELINE_SPECS
from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.rare.config import RareConfig
from evoeye.scenarios import SCENARIO_SPECS, SCENARIOS

BASELINES = BASELINE_SPECS  # the registered baselines' names (evoeye.evaluation.baselines)
CONTEXT_LENS = (1, 3, 5, 7)  # evoeye.evaluation.ablation.CONTEXT_LENS
INPUTS = ("perception", "perception+prediction", "perception+prediction+planning",
          "all")  # evoeye.monitor.inputs.ABLATIONS
METHODS = ("uniform", "avfuzzer", "evoeye", "no-feedback", "no-density",
           "aem-evo")  # evoeye.evolve.campaign.experiment MAIN + ABLATION
PAPER_PARTS = ("rq1", "ablation", "rq2")  # what `evoeye results` runs by default
# + the sample-efficiency study (evoeye.results.efficiency) and the rare-failure protocol
# (evoeye.results.rare): each on data of its own per regime, neither run by default
PARTS = (*PAPER_PARTS, "efficiency", "rare")
# how a campaign's k final monitors are made (evoeye.results.rq2): its last update again with
# k seeds (what a user of the method deploys), or G_0's recipe trained from scratch on its D_R
# with the k seeds of "G_0 (k seeds)" (what the data it acquired is worth, whatever the update)
FINALS = ("update", "retrain")
MONITOR_PARTS = ("rq1", "ablation")  # the parts that train on RQ1's data
# the paper's test runs, and its initial data (train + validation runs, split 0.8 : 0.2), of
# the scenarios it studied (`ScenarioSpec.paper_runs`)
PAPER_TEST_RUNS = {n: s.paper_runs[0] for n, s in SCENARIO_SPECS.items() if s.paper_runs}
PAPER_INITIAL_RUNS = {n: s.paper_runs[1] for n, s in SCENARIO_SPECS.items() if s.paper_runs}
# training recipes (evoeye.monitor.recipes RECIPES, DEFAULT_RECIPE, LEGACY_RECIPE): a config
# recorded before the recipe was one of its fields was trained with the legacy one
RECIPES = ("v1", "v2", "v3", "lookahead-v1")
DEFAULT_RECIPE, LEGACY_RECIPE = "v3", "v1"
RQ1_RUNS = 1300  # initial runs RQ1 and the monitor ablation train on, at least (module doc)
TEST_SHARES = (0.8, 0.2)  # train, val shares of the initial runs when a test batch is held out
DEFAULT_SHARES = (0.5, 0.125)  # evoeye.splits.SplitSpec() (no test batch)


def parse_initial_runs(values: list[str]) -> int | dict[str, int]:
    """`--initial-runs` as given: "N" (every scenario), "SCENARIO=N" (that one; later wins) or
    "paper" (the paper's per scenario, `PAPER_INITIAL_RUNS`), repeatable; ValueError naming a
    value that is none of these."""
    every, per = 0, {}
    for value in values:
        scenario, sep, count = value.rpartition("=")
        if not sep and count == "paper":
            per.update(PAPER_INITIAL_RUNS)
            continue
        try:
            n = int(count)
        except ValueError:
            n = -1
        if n < 0:
            raise ValueError(f"--initial-runs {value!r}: give N, SCENARIO=N or 'paper' "
                             "(N a whole number >= 0)")
        if sep and scenario not in SCENARIOS:
            raise ValueError(f"--initial-runs {value!r}: unknown scenario {scenario!r}; known: "
                             f"{', '.join(SCENARIOS)}")
        if sep:
            per[scenario] = n
        else:
            every, per = n, {}
    return {**dict.fromkeys(SCENARIOS, every), **per} if per else every


@dataclass(frozen=True)
class ResultsConfig:
    """Everything `evoeye results` regenerates, and at what size (module doc)."""

    scenarios: tuple[str, ...] = field(default_factory=lambda: tuple(SCENARIOS))  # registered
    training_seeds: tuple[int, ...] = (0, 1, 2, 3, 4, 5)
    campaign_seeds: tuple[int, ...] = tuple(range(20))
    final_seeds: int = 3  # k: a final monitor is judged by the mean over k training seeds
    final: str = "update"  # FINALS: the k monitors are the last update again, or retrained
    parts: tuple[str, ...] = PAPER_PARTS
    # data: simulated (or resumed) first, then ingested; 0 runs: use what the warehouse holds
    # round-0 runs, batch uniform-seed<sim_seed>: one count for every scenario, or per scenario
    initial_runs: int | Mapping[str, int] = 0
    sim_seed: int = 0
    rq1_runs: int = RQ1_RUNS  # RQ1 and the ablation's initial runs, at least (`rq1_own_data`)
    test_runs: int = 400  # runs per scenario of the held-out Test Set batch
    test_seed: int = 1_000_000
    test_batch: str | None = None  # its name (default test-seed<test_seed> when test_runs > 0)
    split_seed: int = 0
    train_frac: float | None = None  # None: 0.8 with a test batch, else SplitSpec's 0.5
    val_frac: float | None = None  # None: 0.2 with a test batch, else SplitSpec's 0.125
    horizon_s: float = 3.0
    # RQ1 and the monitor ablation
    baselines: tuple[str, ...] = field(default_factory=lambda: tuple(BASELINES))  # registered
    context_lens: tuple[int, ...] = CONTEXT_LENS
    inputs: tuple[str, ...] = INPUTS
    epochs: int | None = None  # every training (None: each trainer's default)
    patience: int | None = None
    recipe: str = DEFAULT_RECIPE  # RECIPES: how every monitor of RQ1, the ablation and the
    # G_0s trains from scratch (campaign updates keep the campaign's own)
    # RQ2, the evolution ablations and AEM-Evo
    methods: tuple[str, ...] = METHODS
    budget_s: float | None = None  # None: the simulated time of the initial training data
    n_round: int = 20
    update: str = "replay"
    feedback: str = "raw"
    workers: int = 1  # processes simulating the data batches, then running campaigns
    # the sample-efficiency study: EfficiencyConfig's fields that differ from its defaults
    efficiency: Mapping[str, Any] = field(default_factory=dict)
    # the rare-failure protocol: RareConfig's fields that differ from its defaults
    rare: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("scenarios", "training_seeds", "campaign_seeds", "parts", "baselines",
                     "context_lens", "inputs", "methods"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        object.__setattr__(self, "efficiency", self.efficiency_config.changed())
        object.__setattr__(self, "rare", self.rare_config.changed())
        if not self.scenarios:
            raise ValueError("give at least one logical scenario")
        if isinstance(self.initial_runs, Mapping):
            runs = dict(self.initial_runs)
            if unknown_runs := sorted(set(runs) - set(SCENARIOS)):
                raise ValueError(f"initial runs given for unknown scenario(s) {unknown_runs}; "
                                 f"known: {', '.join(SCENARIOS)}")
            object.__setattr__(self, "initial_runs",
                               {s: int(runs.get(s, 0)) for s in self.scenarios})
        for name in ("training_seeds", "campaign_seeds"):  # pairs need two seeds at least
            seeds = getattr(self, name)
            if len(seeds) < 2 or len(set(seeds)) != len(seeds):
                raise ValueError(f"need at least 2 distinct {name.replace('_', ' ')}, "
                                 f"got {seeds}")
        if self.final_seeds < 1:
            raise ValueError(f"final_seeds must be >= 1, got {self.final_seeds}")
        if self.final not in FINALS:
            raise ValueError(f"unknown final {self.final!r}; known: {list(FINALS)}")
        unknown = set(self.parts) - set(PARTS)
        if unknown or not self.parts:
            raise ValueError(f"unknown part(s) {sorted(unknown)}; known: {list(PARTS)}")
        for name, least in (("rq1_runs", 0), ("test_runs", 0), ("n_round", 1), ("workers", 1)):
            if getattr(self, name) < least:
                raise ValueError(f"{name} must be >= {least}, got {getattr(self, name)}")
        if bad := {s: n for s in self.scenarios if (n := self.runs_of(s)) < 0}:
            raise ValueError(f"initial runs must be >= 0, got {bad}")
        if self.recipe not in RECIPES:
            raise ValueError(f"unknown training recipe {self.recipe!r}; known: {list(RECIPES)}")
        if self.test_runs and self.test_seed == self.sim_seed:
            raise ValueError("the test batch needs its own seed: --test-seed equals --sim-seed")
        if min(self.training_seeds + self.campaign_seeds + (self.sim_seed, self.test_seed)) < 0:
            raise ValueError("seeds must be non-negative")
        if self.rq1_own_data and not all(map(self.runs_of, self.scenarios)):
            raise ValueError("RQ1's own initial runs start from the study's: give every "
                             "scenario initial runs, or none (0: the warehouse's)")
        if self.rq1_own_data and not self.test_runs:
            raise ValueError(f"RQ1's own {self.rq1_runs} initial runs need the Test Set "
                             "simulated beside them (--test-runs > 0); or give --rq1-runs 0 to "
                             "train RQ1 on the study's initial runs")

    def check_names(self) -> None:
        """ValueError naming any scenario, baseline, input set, method, update or feedback mode
        no registry knows (loads the registries)."""
        from evoeye.evaluation.monitors import BASELINES as KNOWN_BASELINES
        from evoeye.evolve.campaign.config import check_known
        from evoeye.monitor.inputs import ABLATIONS
        from evoeye.splits import SplitSpec

        check_known("scenario", self.scenarios)
        check_known("method", self.methods)
        check_known("update", [self.update])
        check_known("feedback", [self.feedback])
        for kind, given, known in (("baseline", self.baselines, KNOWN_BASELINES),
                                   ("input set", self.inputs, ABLATIONS)):
            if unknown := [n for n in given if n not in known]:
                raise ValueError(f"unknown {kind} {unknown}; known: {sorted(known)}")
        if bad := [n for n in self.context_lens if n < 1]:
            raise ValueError(f"context lengths must be >= 1, got {bad}")
        SplitSpec(self.split_seed, *self.shares, self.held_out_batch)  # shares and batch name
        if "efficiency" in self.parts:
            self.efficiency_config.check_names()
        if "rare" in self.parts:
            self.rare_config.check_names()

    @property
    def efficiency_config(self) -> EfficiencyConfig:
        """The sample-efficiency study's config (ValueError naming a bad field)."""
        return EfficiencyConfig.from_dict(self.efficiency)

    @property
    def rare_config(self) -> RareConfig:
        """The rare-failure protocol's config (ValueError naming a bad field)."""
        return RareConfig.from_dict(self.rare)

    @property
    def paper_parts(self) -> tuple[str, ...]:
        """The parts run per logical scenario on the study's initial data (all but the
        sample-efficiency study and the rare-failure protocol, which have data of their own
        per regime)."""
        return tuple(p for p in self.parts if p in PAPER_PARTS)

    @property
    def held_out_batch(self) -> str | None:
        """The Test Set's batch: named, or test-seed<S> when its runs are simulated."""
        if self.test_batch:
            return self.test_batch
        return f"test-seed{self.test_seed}" if self.test_runs else None

    def runs_of(self, scenario: str) -> int:
        """The initial runs to simulate (or resume) of a scenario (0: the warehouse's)."""
        if isinstance(self.initial_runs, Mapping):
            return self.initial_runs.get(scenario, 0)
        return self.initial_runs

    @property
    def rq1_own_data(self) -> bool:
        """Whether RQ1 and the ablation run on initial runs of their own: they run, and the
        study simulates fewer initial runs than `rq1_runs` of some scenario (with initial runs
        0 every part uses the warehouse's)."""
        return (any(0 < self.runs_of(s) < self.rq1_runs for s in self.scenarios)
                and bool(set(self.parts) & set(MONITOR_PARTS)))

    def rq1_config(self) -> ResultsConfig:
        """The config RQ1 and the ablation run on: this one, or with their own initial runs
        (at least `rq1_runs` of every scenario)."""
        if not self.rq1_own_data:
            return self
        if isinstance(self.initial_runs, Mapping):
            runs: int | dict[str, int] = {s: max(n, self.rq1_runs)
                                          for s, n in self.initial_runs.items()}
        else:
            runs = max(self.initial_runs, self.rq1_runs)
        return replace(self, initial_runs=runs, rq1_runs=0)

    @property
    def shares(self) -> tuple[float, float]:
        """(train_frac, val_frac) of the initial runs."""
        default = TEST_SHARES if self.held_out_batch else DEFAULT_SHARES
        return (default[0] if self.train_frac is None else self.train_frac,
                default[1] if self.val_frac is None else self.val_frac)

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, data: Mapping) -> ResultsConfig:
        """The config a results JSON records (`to_dict`, through JSON); a field it lacks takes
        its default — but the recipe, which a record made before it was a field lacks, is the
        legacy one its monitors were trained with — and a key no field has is a ValueError
        naming it."""
        if unknown := sorted(set(data) - {f.name for f in fields(cls)}):
            raise ValueError(f"unknown config key(s) {unknown}")
        return cls(**{"recipe": LEGACY_RECIPE, **data})
