"""The study's config: validated at once, recorded as what differs, read back the same."""

from __future__ import annotations

import json

import numpy as np
import pytest

from evoeye.results.config import ResultsConfig
from evoeye.results.efficiency.config import EfficiencyConfig, parse_regime, regime_name
from evoeye.results.efficiency.data import boundary_pairs
from evoeye.scenarios import get_scenario


def test_regimes_name_a_scenario_and_a_profile() -> None:
    assert parse_regime("highway-cut-in") == ("highway-cut-in", "default")
    assert parse_regime("unprotected-intersection:firm-yield") == (
        "unprotected-intersection", "firm-yield")
    assert regime_name("highway-cut-in", "default") == "highway-cut-in"
    with pytest.raises(ValueError, match="SCENARIO:PROFILE"):
        parse_regime("a:b:c")


@pytest.mark.parametrize(("change", "message"), [
    ({"mode": "live"}, "mode must be one of"),
    ({"update": "finetune"}, "update must be one of"),
    ({"strategies": ("boundary",)}, "must include the reference 'uniform'"),
    ({"seeds": (3,)}, "at least 2 distinct seeds"),
    ({"checkpoints": (80, 70)}, "must increase"),
    ({"checkpoints": (70, 160)}, "whole rounds of 20"),
    ({"pool_runs": 100}, "must hold the initial runs and the largest budget"),
    ({"members": 0}, "members must be 1 to 8, got 0"),
    ({"members": 9}, "members must be 1 to 8, got 9"),
    ({"val_collisions": -1}, "val_collisions must be >= 0"),
    ({"oracle_step": "run"}, "oracle_step must be one of"),
    ({"oracle_candidates": 3}, "oracle_candidates must be >= 4"),
    ({"mode": "generative", "strategies": ("uniform", "qbc")},
     "^qbc is a pool-mode diagnostic .*: drop it or use mode 'pool'$"),
])
def test_a_bad_config_names_the_problem(change, message) -> None:
    with pytest.raises(ValueError, match=message):
        EfficiencyConfig(**change)


def test_unknown_names_are_refused_with_the_known_ones() -> None:
    with pytest.raises(ValueError, match="ADS profiles"):
        EfficiencyConfig(regimes=("highway-cut-in:reckless",)).check_names()
    with pytest.raises(ValueError, match="unknown strategy \\['annealing'\\]"):
        EfficiencyConfig(strategies=("uniform", "annealing")).check_names()
    with pytest.raises(ValueError, match="\\['subset'\\] propose new points only"):
        EfficiencyConfig(strategies=("uniform", "subset")).check_names()
    EfficiencyConfig(strategies=("uniform", "subset"), mode="generative").check_names()
    EfficiencyConfig().check_names()
    EfficiencyConfig(strategies=("uniform", "qbc")).check_names()  # a study-only diagnostic


def test_a_results_config_records_only_what_differs_and_reads_back_the_same() -> None:
    config = ResultsConfig(parts=("efficiency",), efficiency=EfficiencyConfig(
        mode="generative", seeds=tuple(range(100, 140))).changed())
    recorded = json.loads(json.dumps(config.to_dict()))
    assert recorded["efficiency"] == {"mode": "generative", "seeds": list(range(100, 140))}
    again = ResultsConfig.from_dict(recorded)
    assert again.efficiency_config == config.efficiency_config
    assert again.paper_parts == () and ResultsConfig().paper_parts == ("rq1", "ablation", "rq2")
    with pytest.raises(ValueError, match="unknown efficiency config key"):
        ResultsConfig(efficiency={"pool": 3})


def test_boundary_pairs_join_each_collision_to_its_nearest_safe_run() -> None:
    space = get_scenario("unprotected-intersection")
    rng = np.random.default_rng(0)
    params = space.sample(rng, 60)
    collided = space.normalise(params)[:, 0] > 0.7
    pairs = boundary_pairs(params, collided, space, 5, np.random.default_rng(1))
    u = space.normalise(params)
    assert len(pairs) == 5 and len({h for h, _ in pairs}) == 5
    for hit, safe in pairs:
        assert collided[hit] and not collided[safe]
        d = ((u[~collided] - u[hit]) ** 2).sum(axis=1)
        assert ((u[safe] - u[hit]) ** 2).sum() == pytest.approx(d.min())
    with pytest.raises(ValueError, match="both safe and colliding"):
        boundary_pairs(params, np.zeros(60, bool), space, 5, rng)


def test_the_command_refuses_a_bad_study_before_anything_runs(tmp_path) -> None:
    from typer.testing import CliRunner

    from evoeye.cli import app

    base = ["results", "--part", "efficiency", "--root", str(tmp_path / "r")]
    for extra, message in ((["--regime", "highway-cut-in:reckless"], "ADS profiles"),
                           (["--strategy", "annealing"], "unknown strategy"),
                           (["--mode", "live"], "mode must be one of"),
                           (["--members", "9"], "--members"),
                           (["--oracle-step", "run"], "oracle_step must be one of"),
                           (["--oracle-candidates", "0"], "--oracle-candidates"),
                           (["--mode", "generative", "--strategy", "qbc"],
                            "qbc is a pool-mode diagnostic"),
                           (["--val-collisions", "-1"], "--val-collisions")):
        result = CliRunner().invoke(app, [*base, *extra])
        assert result.exit_code == 2 and message in result.output, result.output
    assert not (tmp_path / "r").exists()


def test_the_later_fields_are_recorded_only_where_set() -> None:
    """A study with one member and the uniform validation batch stores the config it always
    did; one that sets either field records it, and reads back the same."""
    from evoeye.results.efficiency.config import LATER_FIELDS

    assert not set(LATER_FIELDS) & set(EfficiencyConfig().to_dict())
    changed = EfficiencyConfig(members=3, val_collisions=40, oracle_step="round")
    later = {"members": 3, "val_collisions": 40, "oracle_step": "round"}
    assert {k: changed.to_dict()[k] for k in LATER_FIELDS} == later
    assert EfficiencyConfig.from_dict(json.loads(json.dumps(changed.to_dict()))) == changed
    assert ResultsConfig(efficiency=changed.changed()).efficiency == later


def test_the_configs_member_limit_is_the_ensembles() -> None:
    from evoeye.monitor.ensemble import MAX_MEMBERS
    from evoeye.results.efficiency.config import MAX_MEMBERS as SHOWN

    assert SHOWN == MAX_MEMBERS
