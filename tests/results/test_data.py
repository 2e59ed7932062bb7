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
