"""The defaults `--help` shows are the ones the library uses."""

from __future__ import annotations

from evoeye.cli import defaults


def test_help_defaults_equal_their_sources() -> None:
    import evoeye.baselines  # noqa: F401  (registers the baselines' monitor families)
    from evoeye.ads.profiles import ADS_PROFILES
    from evoeye.evolve.campaign.experiment import methods
    from evoeye.evolve.search import STRATEGIES
    from evoeye.monitor.families import evolvable_families
    from evoeye.monitor.inputs import ABLATIONS, MODULES
    from evoeye.monitor.protocol import TARGET_FPRS, WARNING_K
    from evoeye.monitor.recipes import COMMAND_RECIPE, RECIPES
    from evoeye.sim.lockstep import DEFAULT_BATCH
    from evoeye.sim.worlds import WORLD_NAMES
    from evoeye.store import SplitSpec
    from evoeye.store.ingest import DEFAULT_RUNS_PER_PART
    from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S

    split = SplitSpec()
    pairs = {
        "ADS_PROFILE_NAMES": tuple(ADS_PROFILES),
        "WORLD_NAMES": WORLD_NAMES, "DEFAULT_LOCKSTEP": DEFAULT_BATCH,
        "SPLIT_SEED": split.seed, "TRAIN_FRAC": split.train_frac, "VAL_FRAC": split.val_frac,
        "CONTEXT_LEN": DEFAULT_CONTEXT_LEN, "HORIZON_S": DEFAULT_HORIZON_S,
        "TARGET_FPRS": TARGET_FPRS, "WARNING_K": WARNING_K,
        "RUNS_PER_PART": DEFAULT_RUNS_PER_PART,
        "MODULE_NAMES": MODULES, "ABLATION_NAMES": tuple(ABLATIONS),
        "RECIPE_NAMES": tuple(RECIPES), "COMMAND_RECIPE": COMMAND_RECIPE,
        "STRATEGY_NAMES": tuple(STRATEGIES), "FAMILY_NAMES": tuple(evolvable_families()),
        "METHOD_NAMES": tuple(methods()),
    }
    shown = {name: getattr(defaults, name) for name in pairs}
    assert shown == pairs


def test_replay_watch_and_the_reports_count_a_warning_at_one_k() -> None:
    import inspect

    import typer

    from evoeye.cli import app
    from evoeye.evaluation.harness import SCENARIO_KS
    from evoeye.evaluation.headline import operating_point
    from evoeye.monitor.replay import replay

    commands = typer.main.get_command(app).commands
    cli_ks = {name: next(p.default for p in commands[name].params if p.name == "consecutive")
              for name in ("replay", "watch")}
    report = {"fprs": [0.05, 0.01], "ks": list(SCENARIO_KS)}
    assert cli_ks == {"replay": defaults.WARNING_K, "watch": defaults.WARNING_K}
    assert inspect.signature(replay).parameters["consecutive"].default == \
        int(operating_point(report).k) == defaults.WARNING_K


def test_supervise_help_defaults_equal_their_sources() -> None:
    from evoeye.evaluation.supervision.settings import LOG_POLICIES
    from evoeye.evaluation.supervision.summary import BUDGETS_PER_H
    from evoeye.evaluation.supervision.triggers import (
        DEFAULT_BASELINES,
        ORACLE_LEADS_S,
        RECALLS,
        SWEEP_FPRS,
    )
    from evoeye.sim.supervisor import DEFAULT_FALLBACK, FALLBACKS, FallbackConfig

    assert defaults.SWEEP_FPRS == SWEEP_FPRS and defaults.SWEEP_RECALLS == RECALLS
    assert defaults.SUPERVISE_BASELINES == DEFAULT_BASELINES
    assert defaults.SUPERVISE_BUDGETS == BUDGETS_PER_H
    assert defaults.ORACLE_LEADS_S == ORACLE_LEADS_S
    assert defaults.LOG_POLICIES == LOG_POLICIES
    assert {n: f.to_dict() for n, f in FALLBACKS.items()} == defaults.FALLBACKS
    assert DEFAULT_FALLBACK == defaults.DEFAULT_FALLBACK
    assert FallbackConfig() == FALLBACKS[DEFAULT_FALLBACK]


def test_every_known_error_names_an_exception_class_that_exists() -> None:
    import importlib

    from evoeye.cli.errors import KNOWN_ERRORS

    for name in KNOWN_ERRORS:  # keyed by qualified name: a moved class loses its hint silently
        module, cls = name.rsplit(".", 1)
        found = getattr(importlib.import_module(module), cls, None)
        assert isinstance(found, type) and issubclass(found, Exception), name
        assert f"{found.__module__}.{found.__qualname__}" == name  # defined there, not imported
