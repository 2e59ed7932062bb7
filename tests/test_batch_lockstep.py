"""Batches stepped in lockstep (`run_batch(lockstep=B)`): the same logs as one run at a time,
in one process or several; resumable; one broken run or log never stops the others."""

from dataclasses import replace

import pytest

from evoeye import batch
from evoeye.batch import plan_uniform, run_batch
from evoeye.paths import DataRoot
from evoeye.sim import lockstep
from evoeye.sim.runner import SimConfig

SHORT = SimConfig(duration_s=2.0)


@pytest.fixture(autouse=True)
def short_runs(monkeypatch):
    """2 s runs for both engines (each engine is tested at full length in tests/sim)."""
    real_run, real_lockstep = batch.run_episode, lockstep.run_indexed
    monkeypatch.setattr(batch, "run_episode", lambda spec: real_run(spec, SHORT))
    monkeypatch.setattr(batch, "run_indexed",
                        lambda specs, size: real_lockstep(specs, SHORT, size=size))


def logs(root) -> dict:
    return {p.relative_to(root): p.read_bytes() for p in sorted(root.rglob("*.mcap"))}


@pytest.mark.parametrize("workers", [1, 2])
def test_lockstep_batches_write_the_per_run_logs(tmp_path, workers):
    specs = plan_uniform("highway-cut-in", 7, seed=3) + plan_uniform("occluded-crossing", 3, seed=3)
    one = run_batch(specs, DataRoot.resolve(tmp_path / "one"))
    together = run_batch(specs, DataRoot.resolve(tmp_path / "together"), workers=workers,
                         lockstep=4)
    assert [replace(r, path=r.path.replace("/together/", "/one/")) for r in together.results] \
        == one.results
    assert logs(tmp_path / "together") == logs(tmp_path / "one") != {}


def test_a_lockstep_rerun_skips_what_is_on_disk_and_redoes_a_broken_log(tmp_path):
    specs = plan_uniform("highway-cut-in", 5, seed=4)
    root = DataRoot.resolve(tmp_path)
    run_batch(specs[:2], root, lockstep=8)
    broken = root.run_log(specs[2].scenario, specs[2].batch, specs[2].scenario_id)
    broken.write_bytes(b"\x89MCAP0\r\n garbage")
    summary = run_batch(specs, root, lockstep=8)
    assert summary.runs == 5 and summary.skipped == 2 and summary.failures == 0
    assert sorted(p.stem for p in broken.parent.glob("*.mcap")) == sorted(
        s.scenario_id for s in specs)
    assert logs(tmp_path) == logs_of(specs, tmp_path / "ref")


def logs_of(specs, root) -> dict:
    run_batch(specs, DataRoot.resolve(root))
    return logs(root)


def test_a_log_that_cannot_be_written_is_that_runs_error_only(tmp_path, monkeypatch):
    specs = plan_uniform("highway-cut-in", 4, seed=5)
    real = batch.write_episode

    def full_disk(episode, path):
        if episode.spec == specs[2]:
            raise OSError("No space left on device")
        real(episode, path)

    monkeypatch.setattr(batch, "write_episode", full_disk)
    summary = run_batch(specs, DataRoot.resolve(tmp_path), lockstep=4)
    errors = [r for r in summary.results if r.status == "error"]
    assert [r.scenario_id for r in errors] == [specs[2].scenario_id]
    assert "No space left on device" in errors[0].reason
    assert len(list(tmp_path.rglob("*.mcap"))) == 3


def test_collisions_only_keeps_no_log_of_a_safe_run(tmp_path):
    specs = plan_uniform("highway-cut-in", 4, seed=6)  # nothing collides in 2 s
    summary = run_batch(specs, DataRoot.resolve(tmp_path), lockstep=4, collisions_only=True)
    assert summary.runs == 4 and summary.collisions == 0
    assert not any(r.logged for r in summary.results)
    assert not list(tmp_path.rglob("*.mcap"))


def test_lockstep_must_be_positive(tmp_path):
    with pytest.raises(ValueError, match="--lockstep must be at least 1"):
        run_batch(plan_uniform("highway-cut-in", 1, seed=1), DataRoot.resolve(tmp_path),
                  lockstep=0)
