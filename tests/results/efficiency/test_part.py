"""The study as a part of `evoeye results`: workers, summaries, claims, files, resume."""

from __future__ import annotations

import json
from dataclasses import replace

from evoeye.results.config import ResultsConfig
from evoeye.results.efficiency import runner
from evoeye.results.efficiency.part import failed_units, regime_results, run_efficiency
from evoeye.results.efficiency.report import efficiency_markdown, regime_markdown
from evoeye.results.efficiency.restate import main as restate_main
from evoeye.results.efficiency.restate import restate
from evoeye.results.ledger import Ledger
from evoeye.results.run import assemble, write_results
from evoeye.results.study import Study


def test_the_study_runs_in_workers_resumes_and_writes_its_files(tiny_regime, tiny_config,
                                                                 monkeypatch) -> None:
    root, data = tiny_regime
    monkeypatch.setattr(runner, "prepare_regime", lambda *a, **k: data)  # no simulation
    config = replace(tiny_config, strategies=("uniform", "boundary", "qbc"))
    ledger = Ledger(root)
    first = run_efficiency(root, config, workers=2, ledger=ledger)
    regime = first["regimes"][config.regimes[0]]
    measure = regime["summaries"]["test/scratch"]["strategies"]
    assert set(measure) == {"uniform", "boundary", "qbc", "oracle", "oracle-uniform",
                            "oracle-seeds"}
    assert measure["qbc"]["area_vs_reference"]["n"] == 2  # paired with Uniform like any
    assert measure["oracle-seeds"]["area_vs_reference"]["n"] == 2
    assert measure["oracle"]["area_vs_seeds"]["n"] == 2
    assert [m["n"] for m in measure["uniform"]["mean"]] == [2, 2, 2, 2]  # 6, 10, 14, 18 runs
    assert measure["boundary"]["area_vs_reference"]["n"] == 2
    assert measure["oracle"]["area_vs_control"]["n"] == 2  # paired with its control
    assert "area_vs_control" not in measure["boundary"]
    update = regime["summaries"]["test/update"]["strategies"]
    assert not {"oracle", "oracle-uniform", "oracle-seeds", "qbc"} & set(update)  # none
    assert regime["where"]["boundary"]["runs"] == 14 - 6
    assert regime["where"]["oracle-seeds"] == regime["where"]["uniform"]  # Uniform's runs
    assert [f["id"] for f in first["findings"]] == ["efficiency-area", "efficiency-factor",
                                                    "efficiency-ceiling", "efficiency-choice",
                                                    "efficiency-seeds", "efficiency-paper"]
    choice = first["findings"][3]["checks"]
    assert [(c["strategy"], c["against"]) for c in choice] == [("oracle", "oracle-uniform")]
    seeds = first["findings"][4]["checks"]
    assert [(c["strategy"], c["against"]) for c in seeds] == [("oracle", "oracle-seeds")]
    assert all(c["strategy"] != "qbc" for c in first["findings"][0]["checks"])  # a diagnostic

    assert ledger.computed["efficiency-curve"] + ledger.found["efficiency-curve"] == 12
    found = Ledger(root)
    again = run_efficiency(root, config, workers=1, ledger=found)  # every curve found
    assert again == first and found.computed["efficiency-curve"] == 0
    assert found.found["efficiency-curve"] == 12  # 3 strategies, the oracle, 2 controls; 2 seeds
    raw = runner.run_regime(root, config.regimes[0], config, ledger=found)
    retrained = regime_results(raw, replace(config, update="retrain"))["summaries"]
    assert set(retrained) == {"test/scratch", "boundary/scratch"}  # the update one is scratch

    results = ResultsConfig(parts=("efficiency",), efficiency=config.changed())
    folder = write_results(root, assemble(Study(root, results), {}, first), "study")
    text = (folder / "efficiency.md").read_text()
    assert "## highway-cut-in, default ADS" in text and "uniform (reference)" in text
    assert "Oracle − its uniform-only control: area" in text
    assert "Oracle − its best-of-k-training-seeds control: area" in text
    assert "qbc (pool-mode diagnostic)" in text and "(oracle-seeds) chooses no runs" in text
    assert "### Failures found" in text and "Minimum detectable effect" in text
    assert "oracle-seeds's runs are Uniform's" in text
    assert "The oracle picks by true benefit" in text
    assert regime["found"]["14"]["boundary"]["runs"] == 2 * (14 - 6)  # two seeds, initial apart
    assert "Does acquisition earn its budget?" in (folder / "findings.md").read_text()
    assert (folder / "results.html").read_text().count("<svg") == 3  # one chart per summary
    stored = json.loads((folder / "results.json").read_text())["efficiency"]
    assert stored["config"]["strategies"] == ["uniform", "boundary", "qbc"]
    assert restate(stored).strip() == text.strip()  # the stored curves give the same page


def test_a_curve_that_fails_is_named_left_out_and_retried_alone(tiny_regime, tiny_config,
                                                                monkeypatch) -> None:
    root, data = tiny_regime
    monkeypatch.setattr(runner, "prepare_regime", lambda *a, **k: data)
    config = replace(tiny_config, strategies=("uniform",), seeds=(3, 4), oracle=False)
    real = runner.run_curve

    def planted(ctx, strategy, seed, acquirer):
        if seed == 4:
            raise RuntimeError("planted")
        return real(ctx, strategy, seed, acquirer)

    monkeypatch.setattr(runner, "run_curve", planted)
    first = run_efficiency(root, config, workers=2, ledger=Ledger(root))
    regime = first["regimes"][config.regimes[0]]
    assert regime["failed"] == [{"strategy": "uniform", "seed": 4,
                                 "error": "RuntimeError: planted"}]
    assert failed_units(first) == [f"{config.regimes[0]}: uniform seed 4: RuntimeError: planted"]
    assert list(regime["curves"]["uniform"]) == ["3"]  # the other seed went through
    assert "uniform, seed 4: RuntimeError: planted" in regime_markdown(config.regimes[0], regime)

    monkeypatch.setattr(runner, "run_curve", real)
    ledger = Ledger(root)
    again = run_efficiency(root, config, workers=1, ledger=ledger)
    assert again["regimes"][config.regimes[0]]["failed"] == [] and not failed_units(again)
    assert "oracle" not in efficiency_markdown(again).split("\n## ")[0]  # --no-oracle: no word
    assert ledger.computed["efficiency-curve"] == 1 and ledger.found["efficiency-curve"] == 1


def test_restate_names_a_file_without_the_study(tmp_path, capsys) -> None:
    other = tmp_path / "rq1.json"
    other.write_text(json.dumps({"rq1": {}}))
    assert restate_main([str(other)]) == 2
    assert capsys.readouterr().err.strip() == f"{other}: no efficiency part in this results JSON"
