"""The data step: the initial and the held-out batches simulated once, at their own seeds."""

from __future__ import annotations

from dataclasses import asdict

from evoeye.paths import DataRoot
from evoeye.results.config import ResultsConfig
from evoeye.results.study import Study, prepare_data
from evoeye.store import Warehouse

SCENARIO = "highway-cut-in"


def test_the_batches_are_simulated_once_and_the_held_out_one_is_the_test_set(tmp_path) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    cfg = ResultsConfig(scenarios=(SCENARIO,), initial_runs=3, test_runs=2, test_seed=5)
    assert prepare_data(root, cfg) == {SCENARIO: {"uniform-seed0": 3, "test-seed5": 2}}
    logs = {p: p.stat().st_mtime_ns for p in root.runs.rglob("*.mcap")}
    assert {p.parent.name for p in logs} == {"uniform-seed0", "test-seed5"} and len(logs) == 5
    study = Study(root, cfg)
    assert study.splits.test_batch == "test-seed5" and study.splits.train_frac == 0.8
    stats = {r["split"]: r["scenarios"] for r in Warehouse(root).query(
        "initial_split_stats", logical_scenario=SCENARIO, horizon_s=3.0,
        **asdict(study.splits)).to_pylist()}
    assert stats.get("test") == 2 and stats.get("train", 0) + stats.get("val", 0) == 3
    prepare_data(root, cfg)  # again: every run is on disk, nothing is simulated
    assert {p: p.stat().st_mtime_ns for p in root.runs.rglob("*.mcap")} == logs


def test_rq1_runs_on_more_initial_runs_of_its_own_with_the_same_test_set(tmp_path) -> None:
    from evoeye.results.run import part_study, prepare_studies, scenario_data
    from evoeye.results.study import RQ1_DATA

    root = DataRoot.resolve(tmp_path / "data")
    cfg = ResultsConfig(scenarios=(SCENARIO,), initial_runs=2, rq1_runs=3, test_runs=2,
                        test_seed=5)
    study, rq1 = prepare_studies(root, cfg)
    assert rq1.root.path == root.path.joinpath(*RQ1_DATA) and rq1.config.initial_runs == 3
    assert [part_study(study, rq1, p) for p in ("rq1", "ablation", "rq2")] == [rq1, rq1, study]
    ours = {p.relative_to(root.runs): p for p in root.runs.rglob("*.mcap")}
    theirs = {p.relative_to(rq1.root.runs): p for p in rq1.root.runs.rglob("*.mcap")}
    assert len(ours) == 4 and len(theirs) == 5 and set(ours) < set(theirs)
    for name, path in ours.items():  # the study's logs are linked, not simulated again
        assert theirs[name].samefile(path)
    data = scenario_data(study, rq1, SCENARIO)
    main, own = data["data"]["splits"], data["rq1_data"]["splits"]
    assert main["test"]["scenarios"] == own["test"]["scenarios"] == 2
    assert sum(own[s]["scenarios"] for s in own if s != "test") == 3
    assert sum(main[s]["scenarios"] for s in main if s != "test") == 2
    assert rq1.fingerprint(SCENARIO, "test") == study.fingerprint(SCENARIO, "test")
    logs = {p: p.stat().st_mtime_ns for p in rq1.root.runs.rglob("*.mcap")}
    again, _ = prepare_studies(root, cfg)  # again: nothing is linked or simulated
    assert {p: p.stat().st_mtime_ns for p in rq1.root.runs.rglob("*.mcap")} == logs
    assert "rq1_data" not in scenario_data(again, again, SCENARIO)


def test_rq1_md_shows_the_data_rq1_ran_on_and_rq2_md_the_studys() -> None:
    from evoeye.results.run import markdown_files

    def split(runs: int) -> dict:
        return {"scenarios": runs, "violations": 1, "frames": 10, "unsafe_frames": 2}

    results = {
        "config": {"training_seeds": [0, 1], "campaign_seeds": [0, 1], "final_seeds": 1,
                   "rq1_runs": 1300},
        "splits": {"test_batch": "test-seed5", "train_frac": 0.8, "val_frac": 0.2, "seed": 0},
        "scenarios": {SCENARIO: {"data": {"splits": {"train": split(208)}},
                                 "rq1_data": {"splits": {"train": split(1040)}}}},
        "tables": [], "findings": []}
    files = markdown_files(results)
    assert "RQ1's own 1300 initial runs" in files["rq1.md"]
    assert f"| {SCENARIO} | train | 1040 |" in files["rq1.md"]
    assert f"| {SCENARIO} | train | 208 |" in files["rq2.md"] and "1040" not in files["rq2.md"]
    del results["scenarios"][SCENARIO]["rq1_data"]  # RQ1 on the study's runs
    files = markdown_files(results)
    assert f"| {SCENARIO} | train | 208 |" in files["rq1.md"] and "own" not in files["rq1.md"]
