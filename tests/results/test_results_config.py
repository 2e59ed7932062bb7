"""ResultsConfig: its literal defaults match their sources, bad values are refused by name."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from evoeye.results import config
from evoeye.results.config import PAPER_INITIAL_RUNS, ResultsConfig, parse_initial_runs

PAPER = tuple(PAPER_INITIAL_RUNS)  # the paper's scenarios, whatever else is registered
S1, S2 = PAPER


def every(runs: int = 0, **per: int) -> dict[str, int]:
    """`runs` for every registered scenario, except those given per name."""
    return {**dict.fromkeys(config.SCENARIOS, runs), **per}


def test_the_literal_defaults_are_their_sources() -> None:
    from evoeye.evaluation.ablation import CONTEXT_LENS
    from evoeye.evolve.campaign.experiment import ABLATION, MAIN
    from evoeye.monitor.inputs import ABLATIONS
    from evoeye.monitor.recipes import DEFAULT_RECIPE, LEGACY_RECIPE, RECIPES
    from evoeye.splits import SplitSpec

    assert config.CONTEXT_LENS == CONTEXT_LENS
    assert tuple(ABLATIONS) == config.INPUTS
    assert config.METHODS == MAIN + ABLATION
    assert (SplitSpec().train_frac, SplitSpec().val_frac) == config.DEFAULT_SHARES
    assert tuple(RECIPES) == config.RECIPES
    # the sample-efficiency study's copy too: `evoeye results` builds its config whatever the
    # part, so a recipe missing there refused `--part rq1 --recipe lookahead-v1`
    from evoeye.results.efficiency import config as efficiency

    assert tuple(RECIPES) == efficiency.RECIPES and efficiency.DEFAULT_RECIPE == DEFAULT_RECIPE
    assert (config.DEFAULT_RECIPE, config.LEGACY_RECIPE) == (DEFAULT_RECIPE, LEGACY_RECIPE)


def test_the_config_module_imports_nothing_heavy() -> None:
    probe = ("import json, sys; import evoeye.results.config; "
             "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          check=True)
    assert not set(json.loads(done.stdout)) & {"numpy", "torch", "duckdb", "pyarrow", "scipy"}


def test_the_defaults_are_the_issues_sizes() -> None:
    cfg = ResultsConfig()
    assert len(cfg.training_seeds) >= 5 and 2 / 2 ** len(cfg.training_seeds) <= 0.05
    assert 16 <= len(cfg.campaign_seeds) <= 25
    assert all(cfg.test_runs >= 3 * n for n in config.PAPER_TEST_RUNS.values())
    assert cfg.held_out_batch == "test-seed1000000" and cfg.shares == (0.8, 0.2)
    assert ResultsConfig(test_runs=0).shares == config.DEFAULT_SHARES
    assert ResultsConfig(test_runs=0, test_batch="held").held_out_batch == "held"


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"training_seeds": (0,)}, "at least 2 distinct training seeds"),
    ({"campaign_seeds": (1, 1)}, "at least 2 distinct campaign seeds"),
    ({"final_seeds": 0}, "final_seeds must be >= 1"),
    ({"final": "ensemble"}, r"unknown final 'ensemble'; known: \['update', 'retrain'\]"),
    ({"parts": ("rq1", "rq4")}, r"unknown part\(s\) \['rq4'\]"),
    ({"test_seed": 0}, "its own seed"),
    ({"n_round": 0}, "n_round must be >= 1"),
    ({"rq1_runs": -1}, "rq1_runs must be >= 0"),
    ({"initial_runs": 260, "test_runs": 0}, "need the Test Set simulated beside them"),
    ({"initial_runs": {S1: -1}}, r"initial runs must be >= 0, got \{'highway-cut-in': -1\}"),
    ({"initial_runs": {"roundabout": 5}}, r"unknown scenario\(s\) \['roundabout'\]"),
    ({"initial_runs": {S1: 132}, "scenarios": PAPER}, "give every scenario initial runs, or none"),
])
def test_bad_sizes_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        ResultsConfig(**kwargs)


def test_rq1_gets_initial_runs_of_its_own_only_when_the_study_simulates_fewer() -> None:
    small = ResultsConfig(initial_runs=260)
    assert small.rq1_runs == config.RQ1_RUNS and small.rq1_own_data
    own = small.rq1_config()
    assert (own.initial_runs, own.rq1_runs, own.rq1_own_data) == (config.RQ1_RUNS, 0, False)
    assert own.sim_seed == small.sim_seed and own.held_out_batch == small.held_out_batch
    assert own.shares == small.shares and own.training_seeds == small.training_seeds
    for same in (ResultsConfig(initial_runs=config.RQ1_RUNS),  # already enough
                 ResultsConfig(initial_runs=260, rq1_runs=0),  # asked for the study's
                 ResultsConfig(test_runs=0, test_batch="held"),  # the warehouse's runs
                 ResultsConfig(initial_runs=260, parts=("rq2",), test_runs=0)):  # no RQ1
        assert not same.rq1_own_data and same.rq1_config() is same
    assert ResultsConfig(initial_runs=260, parts=("ablation",)).rq1_own_data


@pytest.mark.parametrize(("values", "runs"), [
    ([], 0),
    (["260"], 260),
    (["paper"], every(**PAPER_INITIAL_RUNS)),
    ([f"{S2}=222"], every(**{S2: 222})),
    (["100", f"{S2}=222"], every(100, **{S2: 222})),
    (["paper", f"{S1}=7"], every(**{**PAPER_INITIAL_RUNS, S1: 7})),
    ([f"{S1}=7", "50"], 50),  # a count for every scenario after a per-scenario one: it wins
])
def test_initial_runs_are_one_count_or_per_scenario(values: list[str], runs) -> None:
    assert parse_initial_runs(values) == runs


@pytest.mark.parametrize("value", ["-3", "many", "=5", f"{S1}=", f"{S1}=-1", "paper=3"])
def test_a_bad_initial_runs_value_is_named(value: str) -> None:
    with pytest.raises(ValueError, match=f"--initial-runs '{value}'"):
        parse_initial_runs([value])


def test_the_command_names_a_bad_initial_runs_value_before_it_runs(tmp_path) -> None:
    from typer.testing import CliRunner

    import evoeye.cli.results  # noqa: F401  (registers the command)
    from evoeye.cli import app

    done = CliRunner().invoke(app, ["results", "--root", str(tmp_path / "r"), "--initial-runs",
                                    "paper", "--initial-runs", "highway=5"])
    assert done.exit_code == 2 and "unknown scenario 'highway'" in done.output
    assert not (tmp_path / "r").exists()  # nothing created


def test_per_scenario_initial_runs_reach_each_scenario_and_rq1s_own_data() -> None:
    cfg = ResultsConfig(scenarios=PAPER, initial_runs=PAPER_INITIAL_RUNS)
    assert [cfg.runs_of(s) for s in PAPER] == [132, 222] and cfg.rq1_own_data
    assert cfg.rq1_config().initial_runs == {S1: config.RQ1_RUNS, S2: config.RQ1_RUNS}
    mixed = ResultsConfig(scenarios=PAPER, initial_runs={S1: 132, S2: 2000})  # S2 has enough
    assert mixed.rq1_config().initial_runs == {S1: config.RQ1_RUNS, S2: 2000}
    one = ResultsConfig(scenarios=(S2,), initial_runs=PAPER_INITIAL_RUNS)  # S1's is dropped
    assert one.initial_runs == {S2: 222} and one.runs_of(S1) == 0
    assert not ResultsConfig(scenarios=PAPER, initial_runs={S1: 2000, S2: 1300}).rq1_own_data


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"scenarios": ("roundabout",)}, "unknown scenario"),
    ({"methods": ("evoeye", "random-walk")}, "unknown method"),
    ({"baselines": ("ttc", "radar")}, r"unknown baseline \['radar'\]"),
    ({"inputs": ("lidar",)}, "unknown input set"),
    ({"context_lens": (0, 5)}, "context lengths must be >= 1"),
    ({"train_frac": 0.9, "val_frac": 0.3}, "sum <= 1"),
    ({"test_batch": "../x"}, "not a plain name"),
])
def test_unknown_names_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        ResultsConfig(**kwargs).check_names()


def test_the_papers_data_sizes_run_on_the_papers_scenarios_alone() -> None:
    from evoeye.cli.results import study_scenarios
    from evoeye.scenarios import SCENARIOS

    assert study_scenarios(None, ["paper"]) == tuple(PAPER_INITIAL_RUNS)
    assert set(PAPER_INITIAL_RUNS) < set(SCENARIOS)  # a registered scenario has no paper size
    assert study_scenarios(None, None) == tuple(SCENARIOS)
    assert study_scenarios(["occluded-crossing"], ["paper"]) == ("occluded-crossing",)
