"""`evoeye findings`: the paper's findings over several `evoeye results` runs, each table from
the one run that has it, exactly as one run over everything would check them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.errors import ExitCode
from evoeye.results.combine import ResultsFileError, combine, write_combined
from evoeye.results.config import BASELINES
from evoeye.results.efficiency.findings import MEASURE, efficiency_findings
from evoeye.results.findings import check_findings
from evoeye.results.markdown import README_BEGIN, README_END
from evoeye.results.readme import FIGURE, readme_section, rq1_figure
from evoeye.results.rq1 import FUSION_LABEL
from evoeye.results.tables import build_tables

N = 8
RNG = np.random.default_rng(11)
SETS = ("test", "hard", "robust")


def _seeds(values) -> list[dict]:
    return [{s: {"f1@0.05": v, "f1@0.01": v, "auroc": v, "auprc": v,
                 "reachable@0.05": True, "reachable@0.01": True} for s in SETS}
            for v in values]


def _rq1(gain: float) -> dict:
    """The FusionMonitor about `gain` above every baseline on every seed."""
    base = 0.4 + 0.03 * RNG.standard_normal(N)
    methods = {FUSION_LABEL: {"figures": _seeds(base + gain + 0.01 * RNG.standard_normal(N))}}
    methods.update({b: {"figures": _seeds(base)} for b in BASELINES})
    return {"seeds": list(range(N)), "methods": methods}


def _rq2(gain: float) -> dict:
    base = 0.3 + 0.03 * RNG.standard_normal(N)
    methods = {"G_0": {"figures": _seeds([0.2] * N)},
               "uniform": {"figures": _seeds(base)}, "avfuzzer": {"figures": _seeds(base)},
               "evoeye": {"figures": _seeds(base + gain + 0.01 * RNG.standard_normal(N))}}
    return {"campaign_seeds": list(range(N)), "methods": methods}


def _write(path: Path, parts: dict, config: dict | None = None) -> Path:
    """A results.json as `evoeye results` writes it (config, tables, findings)."""
    tables = build_tables(parts)
    results = {"config": config or {"training_seeds": list(range(N)), "sim_seed": 7},
               "tables": tables, "findings": check_findings(tables)}
    path.mkdir(parents=True, exist_ok=True)
    (path / "results.json").write_text(json.dumps(results, default=float), encoding="utf-8")
    return path / "results.json"


def _verdicts(findings: list[dict]) -> dict[str, str]:
    return {f["id"]: f["verdict"] for f in findings}


def test_each_table_counts_from_its_run_as_if_one_run_had_them_all(tmp_path: Path) -> None:
    rq1 = _write(tmp_path / "a", {"s1": {"rq1": _rq1(0.1)}, "s2": {"rq1": _rq1(0.1)}})
    rq2 = _write(tmp_path / "b", {"s1": {"rq2": _rq2(-0.05)}})
    combined = combine([rq1, tmp_path / "b"])  # a report folder stands for its results.json
    alone = [json.loads(p.read_text())["findings"] for p in (rq1, rq2)]
    assert _verdicts(alone[0])["rq2-hard"] == "not run yet"
    assert _verdicts(alone[1])["rq1-baselines"] == "not run yet"
    verdicts = _verdicts(combined["findings"])
    assert verdicts["rq1-baselines"] == "reproduces"  # every baseline, both scenarios
    assert verdicts["rq2-hard"] == "does not reproduce"  # EvoEye below both, every seed
    every = [*json.loads(rq1.read_text())["tables"], *json.loads(rq2.read_text())["tables"]]
    assert combined["findings"] == check_findings(every)
    assert [s["path"] for s in combined["sources"]] == [str(rq1), str(rq2)]
    assert combined["sources"][0]["tables"] == ["rq1 (s1)", "rq1 (s2)"]


def test_a_table_in_two_runs_is_refused_by_name(tmp_path: Path) -> None:
    a = _write(tmp_path / "a", {"s1": {"rq1": _rq1(0.1)}})
    b = _write(tmp_path / "b", {"s1": {"rq1": _rq1(-0.1)}, "s2": {"rq2": _rq2(0.0)}})
    with pytest.raises(ResultsFileError, match=r"b/results.json: table rq1 \(s1\) is also in "
                                               r".*a/results.json"):
        combine([a, b])


@pytest.mark.parametrize(("text", "message"), [
    (None, "no such results file"),
    ('{"tables": [{"id": "rq1", ', "not a results JSON"),  # truncated
    ('{"config": {}}', "not written by `evoeye results`"),
    ('[1, 2]', "not written by `evoeye results`"),
])
def test_a_bad_results_file_is_named(tmp_path: Path, text: str | None, message: str) -> None:
    good = _write(tmp_path / "good", {"s1": {"rq1": _rq1(0.1)}})
    bad = tmp_path / "bad.json"
    if text is not None:
        bad.write_text(text, encoding="utf-8")
    with pytest.raises(ResultsFileError, match=f"bad.json: {message}"):
        combine([good, bad])


def test_the_command_writes_the_files_and_the_readme_section(tmp_path: Path) -> None:
    a = _write(tmp_path / "a", {"s1": {"rq1": _rq1(0.1)}},
               {"training_seeds": [0, 1, 2, 3, 4, 5], "campaign_seeds": [0, 1], "sim_seed": 60606,
                "test_seed": 60607, "parts": ["rq1"]})  # no campaigns ran: none shown
    b = _write(tmp_path / "b", {"s1": {"rq2": _rq2(0.1)}})
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n{README_BEGIN}\nold\n{README_END}\nrest\n", encoding="utf-8")
    out = tmp_path / "docs"
    runner = CliRunner()
    res = runner.invoke(app, ["findings", str(a), str(b), "--out", str(out),
                              "--readme", str(readme)])
    assert res.exit_code == 0, res.output
    text = (out / "findings.md").read_text(encoding="utf-8")
    assert f"from {out / 'findings.json'}" in text
    assert f"* `{a}`: rq1 (s1) — training seeds 6, sim seed 60606, Test Set seed 60607" in text
    saved = json.loads((out / "findings.json").read_text())
    assert saved == json.loads(json.dumps(combine([a, b]), default=float))
    section = readme_section(saved["findings"], str(out / "findings.json"),
                             command="evoeye findings", details="docs/findings.md")
    assert readme.read_text() == f"intro\n{README_BEGIN}\n{section.strip()}\n{README_END}\nrest\n"
    assert text == write_combined(saved, out)  # rendering is a function of the JSON alone
    assert (out / FIGURE).read_text() == rq1_figure(saved["tables"])  # RQ1's, beside it
    bad = tmp_path / "bad.json"
    bad.write_text("{", encoding="utf-8")
    res = runner.invoke(app, ["findings", str(a), str(bad)])
    assert res.exit_code == ExitCode.USER_ERROR and "bad.json: not a results JSON" in res.output


def test_a_study_run_is_listed_as_the_study_with_its_claims(tmp_path: Path) -> None:
    rq1 = _write(tmp_path / "a", {"s1": {"rq1": _rq1(0.1)}})
    claims = [{"id": "efficiency-area", "claim": "A strategy beats Uniform", "checks": [],
               "verdict": "not run yet"}]
    study = tmp_path / "study.json"
    study.write_text(json.dumps({"config": {"training_seeds": [0]}, "tables": [], "findings": [],
                                 "efficiency": {"config": {"mode": "pool", "seeds": [0, 1],
                                                           "regimes": ["r:cautious"]},
                                                "findings": claims}}))
    combined = combine([rq1, study])
    assert [s["path"] for s in combined["sources"]] == [str(rq1), str(study)]  # reproducible
    text = write_combined(combined)
    assert f"* `{study}`: the sample-efficiency study — its claims are below" in text
    assert "training seeds 1" not in text  # the paper settings a study run does not use
    assert "Does acquisition earn its budget?" in text and "r:cautious" in text
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{README_BEGIN}\nold\n{README_END}\n")
    write_combined(combined, readme=readme)
    section = readme.read_text()
    assert "| A strategy beats Uniform | **not run yet** |" in section
    assert "regimes r:cautious" in section and "old" not in section


def _study(path: Path, regime: str, seeds: list[int], *, gain: bool, mode: str = "pool") -> Path:
    """A study run over one regime whose `boundary` beats Uniform on the area (`gain`) or not."""
    cell = ({"mean_diff": 3.0, "ci_low": 1.0, "ci_high": 5.0, "p_value": 0.002} if gain else
            {"mean_diff": 0.5, "ci_low": -1.0, "ci_high": 2.0, "p_value": 0.4})
    cell["min_p"] = 0.002
    regimes = {regime: {"summaries": {MEASURE: {"strategies": {
        "uniform": {}, "boundary": {"area_vs_reference": cell, "efficiency": None}}}}}}
    config = {"mode": mode, "initial_runs": 40, "seeds": seeds, "regimes": [regime],
              "strategies": ["uniform", "boundary"]}
    path.write_text(json.dumps({"config": {}, "tables": [], "findings": [], "efficiency": {
        "config": config, "regimes": regimes,
        "findings": efficiency_findings({"regimes": regimes})}}))
    return path


def _verdict(findings: list[dict], id_: str) -> str:
    return next(f["verdict"] for f in findings if f["id"] == id_)


def test_a_study_run_regime_by_regime_is_checked_over_all_its_regimes(tmp_path: Path) -> None:
    a = _study(tmp_path / "a.json", "highway-cut-in", list(range(10)), gain=True)
    b = _study(tmp_path / "b.json", "unprotected-intersection", [0, 1, 2, 3], gain=True)
    alone = combine([a])["efficiency"]
    assert _verdict(alone[0]["findings"], "efficiency-area") == "not shown"  # one regime of two
    recorded = json.loads(b.read_text())
    recorded["efficiency"]["config"]["update"] = "replay"  # a key later runs record
    b.write_text(json.dumps(recorded))
    (study,) = combine([a, b])["efficiency"]
    assert study["paths"] == [str(a), str(b)]
    assert _verdict(study["findings"], "efficiency-area") == "reproduces"
    assert study["config"]["seeds"] == {"highway-cut-in": list(range(10)),
                                        "unprotected-intersection": [0, 1, 2, 3]}
    assert ("regimes highway-cut-in (10 seeds (0–9)), unprotected-intersection (4 seeds (0–3))"
            in write_combined(combine([a, b])))
    flat = _study(tmp_path / "c.json", "unprotected-intersection", [0, 1], gain=False)
    assert _verdict(combine([a, flat])["efficiency"][0]["findings"],
                    "efficiency-area") == "not shown"
    # another protocol is another study; the same regime twice in one study is refused
    other = _study(tmp_path / "d.json", "highway-cut-in", [100, 101], gain=True,
                   mode="generative")
    assert [s["paths"] for s in combine([a, b, other])["efficiency"]] == [
        [str(a), str(b)], [str(other)]]
    with pytest.raises(ResultsFileError, match="regime highway-cut-in is also in .*a.json"):
        combine([a, b, _study(tmp_path / "e.json", "highway-cut-in", [0, 1], gain=True)])
