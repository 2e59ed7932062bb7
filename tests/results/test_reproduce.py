"""`evoeye reproduce`: the plan a findings file records, read back; what it refuses, by name.
(Regenerating a whole findings file from it, on the roots that made it, is in
test_end_to_end.py.)"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.errors import ExitCode
from evoeye.results.config import ResultsConfig
from evoeye.results.reproduce import PlanError, read_plan, reproduce

RUNNER = CliRunner()


def _findings(folder: Path, *configs: dict, names: tuple[str, ...] = ("rq1", "rq2")) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    sources = [{"path": f"elsewhere/{name}.json", "config": cfg, "tables": []}
               for name, cfg in zip(names, configs, strict=False)]
    (folder / "findings.json").write_text(json.dumps({"sources": sources, "tables": [],
                                                      "findings": []}))
    return folder


def test_a_config_survives_the_results_json() -> None:
    config = ResultsConfig(scenarios=("unprotected-intersection",), parts=("rq1", "ablation"),
                           training_seeds=(0, 1, 2), initial_runs={"unprotected-intersection": 7},
                           test_seed=5, baselines=("ttc-2d",), context_lens=(1, 5), workers=2)
    assert ResultsConfig.from_dict(json.loads(json.dumps(config.to_dict()))) == config
    # an older file: the defaults, but the recipe its monitors were trained with
    assert ResultsConfig.from_dict({}) == ResultsConfig(recipe="v1") != ResultsConfig()
    assert ResultsConfig().recipe == "v3"
    with pytest.raises(ValueError, match=r"unknown config key\(s\) \['colour'\]"):
        ResultsConfig.from_dict({"colour": 1})


def test_the_plan_is_each_run_beside_the_findings_file_with_its_config(tmp_path) -> None:
    rq1 = ResultsConfig(parts=("rq1",), training_seeds=(0, 1, 2)).to_dict()
    rq2 = ResultsConfig(parts=("rq2",), campaign_seeds=tuple(range(5))).to_dict()
    plan = read_plan(_findings(tmp_path / "docs", rq1, json.loads(json.dumps(rq2))))
    assert [(r.name, r.path) for r in plan] == [("rq1", tmp_path / "docs" / "rq1.json"),
                                                ("rq2", tmp_path / "docs" / "rq2.json")]
    assert plan[0].config.training_seeds == (0, 1, 2) and plan[0].config.parts == ("rq1",)
    assert plan[1].config.campaign_seeds == tuple(range(5))
    assert read_plan(tmp_path / "docs" / "findings.json") == plan  # the file, or its folder


@pytest.mark.parametrize(("content", "message"), [
    (None, "no such findings file"),
    ("{not json", "not a findings JSON"),
    (json.dumps({"sources": []}), "no runs recorded"),
    (json.dumps({"sources": [{"config": {}}]}), "a run without its results file"),
    (json.dumps({"sources": [{"path": "a/x.json", "config": {"final_seeds": 0}}]}),
     "run 'x' cannot be re-run: final_seeds must be >= 1"),
    (json.dumps({"sources": [{"path": "a/x.json", "config": {"colour": 1}}]}),
     "run 'x' cannot be re-run: unknown config key"),
    (json.dumps({"sources": [{"path": "a/x.json"}, {"path": "b/x.json"}]}),
     "two runs are named 'x'"),
])
def test_a_findings_file_that_records_no_runnable_plan_is_refused_by_name(
        tmp_path, content: str | None, message: str) -> None:
    if content is not None:
        (tmp_path / "findings.json").write_text(content)
    with pytest.raises(PlanError, match=message) as err:
        read_plan(tmp_path / "findings.json")
    assert str(tmp_path / "findings.json") in str(err.value)


def test_a_root_for_no_run_is_refused_before_anything_runs(tmp_path) -> None:
    docs = _findings(tmp_path / "docs", {}, {})
    with pytest.raises(PlanError, match=r"root given for no run .*\['rq3'\].*\['rq1', 'rq2'\]"):
        reproduce(docs, tmp_path / "data", roots={"rq3": tmp_path / "x"})
    with pytest.raises(PlanError, match=r"--only for no run .*\['rq3'\]"):
        reproduce(docs, tmp_path / "data", only=["rq3"])
    with pytest.raises(PlanError, match=r"rq1.json'\] missing: re-run those runs too"):
        reproduce(docs, tmp_path / "data", only=["rq2"])  # rq1 kept, but it has no file
    assert not (tmp_path / "data").exists() and not (tmp_path / "x").exists()


def test_the_command_names_a_bad_plan_or_root_and_exits_as_a_user_error(tmp_path) -> None:
    res = RUNNER.invoke(app, ["reproduce", str(tmp_path / "none.json")])
    assert res.exit_code == ExitCode.USER_ERROR and "none.json: no such findings file" in res.output
    docs = _findings(tmp_path / "docs", {})
    res = RUNNER.invoke(app, ["reproduce", str(docs), "--root", "rq1"])
    assert res.exit_code != 0 and "give NAME=PATH" in res.output
    res = RUNNER.invoke(app, ["reproduce", str(docs), "--root", "rq9=/x"])
    assert res.exit_code == ExitCode.USER_ERROR and "['rq9']" in res.output


def test_a_run_naming_an_unknown_method_is_refused_before_the_first_run_starts(tmp_path) -> None:
    docs = _findings(tmp_path / "docs", {"parts": ["rq1"]}, {"methods": ["evoeye", "magic"]})
    with pytest.raises(PlanError, match=r"run 'rq2' cannot be re-run: unknown method"):
        reproduce(docs, tmp_path / "data")
    assert not (tmp_path / "data").exists()  # rq1, first in the plan, did not start
