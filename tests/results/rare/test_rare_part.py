"""The rare-failure protocol as a part of `evoeye results` and of `evoeye findings`: its
config in the results config, its files, a failed curve, a re-run, and the combined claims."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from rare_curves import COMMON, RARE, rare_part
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.results import combine as combine_module
from evoeye.results.combine import ResultsFileError, combine, write_combined
from evoeye.results.config import PAPER_PARTS, ResultsConfig
from evoeye.results.markdown import README_BEGIN, README_END
from evoeye.results.rare import part as rare_part_module
from evoeye.results.rare.config import RareConfig

TINY = ["--part", "rare", "--rare-regime", RARE, "--rare-seeds", "2", "--rare-runs", "2",
        "--rare-batch", "2", "--no-rare-explain"]


def test_a_results_config_records_only_what_differs_and_is_not_run_by_default() -> None:
    config = ResultsConfig(parts=("rare",), rare=RareConfig(seeds=(5, 6), runs=40).changed())
    recorded = json.loads(json.dumps(config.to_dict()))
    assert recorded["rare"] == {"seeds": [5, 6], "runs": 40}
    assert ResultsConfig.from_dict(recorded).rare_config == config.rare_config
    assert "rare" not in ResultsConfig().parts and config.paper_parts == ()
    assert set(PAPER_PARTS) == set(ResultsConfig().parts)
    with pytest.raises(ValueError, match="unknown rare-failure config key"):
        ResultsConfig(rare={"run": 3})


def test_the_command_refuses_a_bad_protocol_before_anything_runs(tmp_path) -> None:
    base = ["results", "--root", str(tmp_path / "r"), *TINY]
    for extra, message in ((["--rare-strategy", "boundary"], "need a monitor"),
                           (["--rare-regime", "highway-cut-in:reckless"], "ADS profiles"),
                           (["--rare-runs", "3"], "whole batches")):
        result = CliRunner().invoke(app, [*base, *extra])
        assert result.exit_code == 2 and message in result.output, result.output
    assert not (tmp_path / "r").exists()


def test_the_part_writes_its_files_names_a_failed_curve_and_resumes(tmp_path,
                                                                    monkeypatch) -> None:
    real = rare_part_module.run_curve

    def planted(config, regime, strategy, seed):
        if strategy == "ce-is" and seed == 1:
            raise RuntimeError("planted")
        return real(config, regime, strategy, seed)

    monkeypatch.setattr(rare_part_module, "run_curve", planted)
    args = ["results", "--root", str(tmp_path / "r"), *TINY]
    first = CliRunner().invoke(app, args)
    assert first.exit_code == 1, first.output
    assert f"{RARE}: ce-is seed 1: RuntimeError: planted" in first.output
    folder = tmp_path / "r" / "reports" / "results"
    stored = json.loads((folder / "results.json").read_text())["rare"]
    assert stored["failed"] == [{"regime": RARE, "strategy": "ce-is", "seed": 1,
                                 "error": "RuntimeError: planted"}]
    assert "* ce-is, seed 1: RuntimeError: planted" in (folder / "rare.md").read_text()

    monkeypatch.setattr(rare_part_module, "run_curve", real)
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 0, again.output
    assert "{'rare-curve': 1}" in again.output  # the failed curve alone, the rest found
    results = json.loads((folder / "results.json").read_text())
    rare = results["rare"]
    assert results["config"]["rare"] == {"regimes": [RARE], "seeds": [0, 1], "runs": 2,
                                         "batch": 2, "explain": False}
    assert rare["failed"] == [] and "computed" not in rare
    assert rare["regimes"][RARE]["found"]["ce-is"]["runs"] == 4
    assert [f["id"] for f in rare["findings"]] == ["rare-found", "rare-estimate", "rare-learn"]
    assert rare["findings"][0]["checks"][0]["cell"]["n"] == 2
    text = (folder / "rare.md").read_text()
    assert "## highway-cut-in, cautious ADS" in text and "### Failures found" in text
    assert "Does testing find and measure rare failures" in (folder / "findings.md").read_text()
    assert "<h2>Rare failures</h2>" in (folder / "results.html").read_text()
    before = (folder / "results.json").read_bytes()
    assert CliRunner().invoke(app, args).exit_code == 0
    assert (folder / "results.json").read_bytes() == before  # a re-run writes the same bytes


def _write(path: Path, rare: dict) -> Path:
    path.write_text(json.dumps({"config": {"parts": ["rare"]}, "tables": [], "findings": [],
                                "rare": rare}))
    return path


def test_findings_carries_the_claims_merged_over_the_protocols_runs(tmp_path) -> None:
    a = _write(tmp_path / "a.json", rare_part({RARE: "rare"}))
    b = _write(tmp_path / "b.json", rare_part({COMMON: "rare"}))
    combined = combine([a, b])
    (protocol,) = combined["rare"]
    assert protocol["paths"] == [str(a), str(b)]
    assert [f["verdict"] for f in protocol["findings"]] == ["reproduces", "reproduces",
                                                            "not run yet"]
    checks = protocol["findings"][0]["checks"]
    assert {c["regime"] for c in checks} == {RARE, COMMON}
    assert all({"regime", "strategy", "metric", "cell", "verdict"} <= c.keys() for c in checks)
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n{README_BEGIN}\nold\n{README_END}\n")
    text = write_combined(combined, tmp_path / "out", readme)
    assert f"* `{a}`: the rare-failure protocol — its claims are below" in text
    assert f"From `{a}`, `{b}`: 200 runs per seed and strategy" in text
    saved = json.loads((tmp_path / "out" / "findings.json").read_text())
    assert saved["rare"][0]["findings"][0]["checks"][0]["cell"]["n"] == 20
    section = readme.read_text()
    assert "The rare-failure protocol: 200 runs per seed and strategy" in section
    assert "| Its failure-rate estimate is unbiased and has ≥ 3× smaller relative error at " \
           "equal budget | **reproduces** |" in section
    with pytest.raises(ResultsFileError, match=f"rare-failure regime {RARE} is also in"):
        combine([a, b, _write(tmp_path / "c.json", rare_part({RARE: "common"}))])
    assert combine_module.RESULTS_FILE == "results.json"


def test_a_rare_run_reproduces_its_own_markdown_and_copies_rare_md_to_docs(tmp_path) -> None:
    from evoeye.paths import DataRoot
    from evoeye.results.reproduce import run_markdown
    from evoeye.results.run import assemble, write_results
    from evoeye.results.study import Study

    root = DataRoot.resolve(tmp_path / "r")
    config = ResultsConfig(parts=("rare",), rare=RareConfig(regimes=(RARE,)).changed())
    results = assemble(Study(root, config), {}, rare=rare_part({RARE: "rare"}))
    text = run_markdown(results)
    assert text.startswith("# Rare failures") and "Monitoring effectiveness" not in text
    write_results(root, results, "rare", docs=tmp_path / "docs")
    assert (tmp_path / "docs" / "rare.md").read_text() == (
        root.reports / "rare" / "rare.md").read_text()


def test_a_fresh_data_seed_moves_every_run_and_is_recorded(tmp_path) -> None:
    """--data-seed reaches both studies' configs; the protocol's runs are those of that seed."""
    args = ["results", "--root", str(tmp_path / "r"), *TINY, "--data-seed", "4242"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    results = json.loads((tmp_path / "r" / "reports" / "results" / "results.json").read_text())
    assert results["config"]["rare"]["data_seed"] == 4242
    assert results["config"]["efficiency"] == {"data_seed": 4242}
    config = RareConfig(regimes=(RARE,), seeds=(0, 1), runs=2, batch=2, explain=False,
                        data_seed=4242)
    curve = rare_part_module.run_curve(config, RARE, "uniform", 0)
    stored = results["rare"]["regimes"][RARE]["found"]["uniform"]
    assert stored["runs"] == 4 and curve["x"] != rare_part_module.run_curve(
        RareConfig(regimes=(RARE,), seeds=(0, 1), runs=2, batch=2, explain=False), RARE,
        "uniform", 0)["x"]
