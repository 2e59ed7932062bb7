"""The defaults `--help` shows are the ones the library uses."""

from __future__ import annotations

from evoeye.cli import defaults


def test_help_defaults_equal_their_sources() -> None:
    from evoeye.evaluation.monitors import BASELINES
    from evoeye.evolve.config import UPDATE_MODES
    from evoeye.monitor.inputs import ABLATIONS, MODULES
    from evoeye.monitor.protocol import TARGET_FPRS
    from evoeye.scenarios import SCENARIOS
    from evoeye.store import SplitSpec
    from evoeye.store.ingest import DEFAULT_RUNS_PER_PART
    from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S

    split = SplitSpec()
    assert defaults.SCENARIO_NAMES == tuple(SCENARIOS)
    assert (defaults.SPLIT_SEED, defaults.TRAIN_FRAC, defaults.VAL_FRAC) == (
        split.seed, split.train_frac, split.val_frac)
    assert defaults.CONTEXT_LEN == DEFAULT_CONTEXT_LEN
    assert defaults.HORIZON_S == DEFAULT_HORIZON_S
    assert defaults.TARGET_FPRS == TARGET_FPRS
    assert defaults.RUNS_PER_PART == DEFAULT_RUNS_PER_PART
    assert defaults.BASELINE_NAMES == tuple(BASELINES)
    assert defaults.UPDATE_MODES == UPDATE_MODES
    assert defaults.MODULE_NAMES == MODULES and defaults.ABLATION_NAMES == tuple(ABLATIONS)
