"""Batches: planned, simulated and logged; safe to kill and re-run; failures isolated."""

from dataclasses import replace

import numpy as np
import pytest
from typer.testing import CliRunner

from evoeye.batch import plan_uniform, run_batch
from evoeye.cli import app
from evoeye.log import read_run
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIO_SPECS
from evoeye.sim import runner
from evoeye.sim.runner import SimConfig

SHORT = SimConfig(duration_s=1.0)


@pytest.fixture(autouse=True)
def short_runs(monkeypatch):
    """Keep batch tests fast: 1 s runs (the runner itself is tested at full length)."""
    real = runner.run_episode
    monkeypatch.setattr("evoeye.batch.run_episode", lambda spec: real(spec, SHORT))


def test_plan_is_reproducible_and_ids_are_distinct():
    a = plan_uniform("unprotected-intersection", 8, seed=3)
    b = plan_uniform("unprotected-intersection", 8, seed=3)
    assert a == b
    assert len({s.scenario_id for s in a}) == 8
    assert a != plan_uniform("unprotected-intersection", 8, seed=4)
    assert all(s.batch == "uniform-seed3" and s.source == "uniform" for s in a)


def test_plan_rejects_bad_sizes():
    with pytest.raises(ValueError, match="--n"):
        plan_uniform("highway-cut-in", 0, seed=1)
    with pytest.raises(ValueError, match="--seed"):
        plan_uniform("highway-cut-in", 2, seed=-1)


def test_batch_writes_one_log_per_run_and_rerun_skips_them(tmp_path):
    specs = plan_uniform("highway-cut-in", 3, seed=1)
    first = run_batch(specs, DataRoot.resolve(tmp_path))
    assert first.runs == 3 and first.skipped == 0 and first.failures == 0
    logs = sorted((tmp_path / "runs" / "highway-cut-in" / "uniform-seed1").glob("*.mcap"))
    assert [p.stem for p in logs] == sorted(s.scenario_id for s in specs)
    before = {p: p.read_bytes() for p in logs}
    again = run_batch(specs, DataRoot.resolve(tmp_path))
    assert again.skipped == 3 and again.simulated_s == 0.0
    assert {p: p.read_bytes() for p in logs} == before
    assert [r.collided for r in again.results] == [r.collided for r in first.results]


def test_killed_batch_resumes_without_duplicates(tmp_path):
    specs = plan_uniform("highway-cut-in", 3, seed=2)
    run_batch(specs[:1], DataRoot.resolve(tmp_path))  # the first run finished before the kill
    folder = tmp_path / "runs" / "highway-cut-in" / "uniform-seed2"
    (folder / f"{specs[1].scenario_id}.mcap.tmp").write_bytes(b"half a log")  # killed mid-write
    (folder / f"{specs[2].scenario_id}.mcap").write_bytes(b"\x89MCAP0\r\n garbage")
    summary = run_batch(specs, DataRoot.resolve(tmp_path))
    assert summary.skipped == 1 and summary.failures == 0
    finals = sorted(p.stem for p in folder.glob("*.mcap"))
    assert finals == sorted(s.scenario_id for s in specs)
    for p in folder.glob("*.mcap"):
        assert read_run(p).metadata["scenario_id"] == p.stem


@pytest.mark.parametrize("scenario", ["unprotected-intersection", "occluded-crossing"])
def test_the_same_seed_gives_byte_identical_logs(tmp_path, scenario):
    specs = plan_uniform(scenario, 2, seed=5)
    run_batch(specs, DataRoot.resolve(tmp_path / "a"))
    run_batch(specs, DataRoot.resolve(tmp_path / "b"), workers=2)
    for s in specs:
        rel = f"runs/{s.scenario}/{s.batch}/{s.scenario_id}.mcap"
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes()


def test_one_broken_run_does_not_stop_the_batch(tmp_path, monkeypatch):
    specs = plan_uniform("highway-cut-in", 3, seed=6)
    bad = specs[1].scenario_id
    real = runner.world_builder("highway-cut-in")

    def sometimes_broken(params, rng):
        if np.isclose(params["ego_speed_mps"], specs[1].params[0]):
            raise RuntimeError("boom")
        return real(params, rng)

    monkeypatch.setitem(SCENARIO_SPECS, "highway-cut-in",
                        replace(SCENARIO_SPECS["highway-cut-in"], world=sometimes_broken))
    summary = run_batch(specs, DataRoot.resolve(tmp_path))
    by_id = {r.scenario_id: r for r in summary.results}
    assert by_id[bad].status == "failed" and "boom" in by_id[bad].reason
    assert summary.failures == 1 and summary.runs == 3
    meta = read_run(by_id[bad].path).metadata  # the failure and its reason are on disk
    assert meta["status"] == "failed" and "boom" in meta["reason"]


def test_cli_simulate_prints_a_summary_and_rejects_bad_input(tmp_path):
    cli = CliRunner()
    ok = cli.invoke(app, ["simulate", "--scenario", "highway-cut-in", "--n", "2",
                          "--root", str(tmp_path)])
    assert ok.exit_code == 0, ok.output
    assert "highway-cut-in" in ok.output and "collisions" in ok.output
    assert len(list(tmp_path.rglob("*.mcap"))) == 2
    bad = cli.invoke(app, ["simulate", "--scenario", "roundabout", "--root", str(tmp_path)])
    assert bad.exit_code == 2 and "unknown logical scenario" in bad.output
    zero = cli.invoke(app, ["simulate", "--scenario", "highway-cut-in", "--n", "0"])
    assert zero.exit_code != 0
