"""A study: one `ResultsConfig` over one data root — its data, its splits and its ledger.

The data comes first: the initial runs (batch `uniform-seed<sim_seed>`) and the held-out Test Set
batch (`test-seed<test_seed>`, its own seed) are simulated or resumed (`run_batch` skips the runs
on disk) and ingested (which adds only what is new). Every monitor then trains on the round-0
train split only — runs acquired by campaigns are round >= 1 and would otherwise join it — is
early-stopped and calibrated on the val split, and is judged on the test split.

RQ1 and the monitor ablation train on at least `rq1_runs` initial runs (`ResultsConfig`). When
the study has fewer, they run on a study of their own (`monitor_study`): the same config with
`rq1_runs` initial runs, on a data root under `<root>/results/rq1-data/`, whose logs start as
links to the study's — its initial runs (the first of the larger batch: `plan_uniform` draws
the same runs for the same seed whatever their number) and its Test Set — so both judge on the
same Test Set, while RQ2's D_init, G_0 and val split stay the study's.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable
from functools import cached_property

from evoeye.evaluation.dataset import SplitWindows, load_split
from evoeye.paths import LOG_SUFFIX, DataRoot
from evoeye.results.config import LEGACY_RECIPE, ResultsConfig
from evoeye.results.ledger import Ledger
from evoeye.store import RunFilter, SplitSpec, Warehouse, select_runs

Progress = Callable[[str], None]
RQ1_DATA = ("results", "rq1-data")  # RQ1's own data root, under the study's root


class EmptySplitError(ValueError):
    """A split the study needs holds no run."""


class Study:
    """The data, splits, fingerprints, windows and ledger one results run shares."""

    def __init__(self, root: DataRoot, config: ResultsConfig,
                 progress: Progress | None = None) -> None:
        self.root = root
        self.config = config
        self.say: Progress = progress or (lambda msg: None)
        self.ledger = Ledger(root)
        self._windows: dict[tuple[str, str], SplitWindows] = {}
        self._fingerprints: dict[tuple[str, str], str] = {}

    @cached_property
    def splits(self) -> SplitSpec:
        train, val = self.config.shares
        return SplitSpec(self.config.split_seed, train, val, self.config.held_out_batch)

    @property
    def train_overrides(self) -> dict[str, int]:
        """Training options every monitor of the study gets (epochs, patience)."""
        return {k: v for k, v in (("epochs", self.config.epochs),
                                  ("patience", self.config.patience)) if v is not None}

    def recipe_key(self, family: str) -> dict[str, str]:
        """What a unit training `family` adds to its ledger inputs for the study's training
        recipe: nothing for the legacy recipe (units recorded before recipes had names keep
        their keys) or a family that has no recipes, else {"training_recipe": name}."""
        from evoeye.monitor.families import FAMILIES

        if self.config.recipe == LEGACY_RECIPE or not FAMILIES[family].recipes:
            return {}
        return {"training_recipe": self.config.recipe}

    def recipe_kwargs(self, family: str) -> dict[str, str]:
        """The study's training recipe as an argument of `family`'s train and fit ({} for a
        family that has no recipes)."""
        from evoeye.monitor.families import FAMILIES

        return {"recipe": self.config.recipe} if FAMILIES[family].recipes else {}

    @property
    def context_len(self) -> int:
        """The longest context any monitor of the study reads (windows are loaded at it): the
        ablation's, and RQ1's FusionMonitor's under the study's recipe."""
        from evoeye.results.rq1 import fusion_context_len

        return max((5, *self.config.context_lens, fusion_context_len(self.config.recipe)))

    def runs(self, scenario: str, split: str) -> RunFilter:
        """A split's runs; train holds round-0 runs only (the initial data, D_init)."""
        return RunFilter(logical_scenario=scenario, split=split, splits=self.splits,
                         max_round=0 if split == "train" else None)

    def fingerprint(self, scenario: str, split: str) -> str:
        """sha256 of the split's run ids: a unit that read the split is keyed by it."""
        key = (scenario, split)
        if key not in self._fingerprints:
            con = Warehouse(self.root).connect()
            try:
                ids = sorted(select_runs(con, self.runs(scenario, split))
                             .column("scenario_id").to_pylist())
            finally:
                con.close()
            if not ids:
                raise EmptySplitError(f"{scenario}: the {split} split has no runs under "
                                 f"{self.root.path} (splits {self.splits}): simulate and "
                                 "ingest more, or check --test-batch and the shares")
            self._fingerprints[key] = hashlib.sha256("\n".join(ids).encode()).hexdigest()
        return self._fingerprints[key]

    def data_key(self, scenario: str, *splits: str) -> dict:
        """What a unit reading these splits of `scenario` depends on (ledger inputs)."""
        return {"scenario": scenario, "horizon_s": self.config.horizon_s,
                **{split: self.fingerprint(scenario, split) for split in splits}}

    def windows(self, scenario: str, split: str) -> SplitWindows:
        """A split's windows at the study's longest context (loaded once)."""
        key = (scenario, split)
        if key not in self._windows:
            self._windows[key] = load_split(self.root, scenario, split, self.splits,
                                            context_len=self.context_len,
                                            horizon_s=self.config.horizon_s)
        return self._windows[key]


def prepare_data(root: DataRoot, config: ResultsConfig, progress: Progress | None = None
                 ) -> dict[str, dict[str, int]]:
    """Simulate (or resume) the initial and held-out batches the config asks for, then ingest
    every log not yet in the warehouse; per scenario and batch, the runs planned."""
    from evoeye.batch import plan_uniform, run_batch
    from evoeye.store import ingest

    say = progress or (lambda msg: None)
    planned: dict[str, dict[str, int]] = {}
    for scenario in config.scenarios:
        batches = []
        if runs := config.runs_of(scenario):
            batches.append((f"uniform-seed{config.sim_seed}", runs, config.sim_seed))
        if config.test_runs:
            batches.append((config.held_out_batch, config.test_runs, config.test_seed))
        for batch, n, seed in batches:
            say(f"{scenario}: simulating batch {batch} ({n} runs, seed {seed})")
            run_batch(plan_uniform(scenario, n, seed, batch=batch), root,
                      workers=config.workers)
            planned.setdefault(scenario, {})[batch] = n
    say("ingesting new logs")
    ingest(root, workers=config.workers)
    return planned


def monitor_study(study: Study) -> Study:
    """The study RQ1 and the monitor ablation run on: `study`, or one with their own initial
    runs on a data root under the study's (module doc)."""
    config = study.config.rq1_config()
    if config is study.config:
        return study
    return Study(DataRoot(study.root.path.joinpath(*RQ1_DATA)), config, study.say)


def share_logs(source: DataRoot, target: DataRoot, config: ResultsConfig) -> int:
    """Link (or copy, across devices) into `target` the logs of `source` that `target` needs:
    those of its initial runs the source has, and every log of the Test Set batch, so both
    judge on the same runs and nothing is simulated twice; the number of logs linked. Logs are
    written once and never changed, so a link is a copy."""
    from evoeye.batch import plan_uniform

    linked = 0
    for scenario in config.scenarios:
        initial = f"uniform-seed{config.sim_seed}"
        runs = config.runs_of(scenario)
        wanted = [source.run_log(scenario, initial, spec.scenario_id) for spec in
                  plan_uniform(scenario, runs, config.sim_seed, batch=initial)] if runs else []
        if config.held_out_batch:
            wanted += sorted(source.batch_dir(scenario, config.held_out_batch)
                             .glob(f"*{LOG_SUFFIX}"))
        for src in wanted:
            dst = target.path / src.relative_to(source.path)
            if src.is_file() and not dst.exists():
                dst.parent.mkdir(parents=True, exist_ok=True)
                try:
                    os.link(src, dst)
                except OSError:
                    shutil.copy2(src, dst)
                linked += 1
    return linked
