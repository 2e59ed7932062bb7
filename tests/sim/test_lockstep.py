"""The lockstep engine gives every run exactly what `run_episode` gives it: the same log bytes.

Runs of every scenario and two ADS profiles (collisions among them), in batches smaller than
the run count so that runs end at different frames and batches are chunked; a run that raises
ends alone; chunks keep one scenario, profile and world per batch."""

import io

import pytest

from evoeye.ads.control import PurePursuitController
from evoeye.ads.lockstep import stack
from evoeye.batch import plan_uniform
from evoeye.log.writer import write_stream
from evoeye.scenarios import SCENARIOS
from evoeye.sim import runner
from evoeye.sim.episode import STATUS_FAILED, STATUS_OK
from evoeye.sim.lockstep import batch_size, chunks, run_lockstep
from evoeye.sim.npc import Npc
from evoeye.sim.runner import SimConfig, run_episode

SHORT = SimConfig(duration_s=8.0)


def log_bytes(episode) -> bytes:
    out = io.BytesIO()
    write_stream(episode, out)
    return out.getvalue()


def by_id(episodes: list) -> dict:
    out = {e.spec.scenario_id: e for e in episodes}
    assert len(out) == len(episodes)  # every run once
    return out


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
@pytest.mark.parametrize("ads", ["default", "cautious"])
def test_every_run_is_the_per_run_engines_run_byte_for_byte(scenario, ads):
    specs = plan_uniform(scenario, 10, seed=31, ads=ads)
    got = list(run_lockstep(specs, SHORT, size=4))
    assert sorted(e.spec.scenario_id for e in got) == sorted(s.scenario_id for s in specs)
    for episode in got:
        ref = run_episode(episode.spec, SHORT)
        assert episode.outcome == ref.outcome
        assert log_bytes(episode) == log_bytes(ref)


def test_runs_that_collide_end_early_and_still_match():
    specs = plan_uniform("highway-cut-in", 16, seed=5)  # 5 of these 16 collide
    got = by_id(list(run_lockstep(specs, size=16)))
    collided = [e for e in got.values() if e.outcome.collided]
    assert collided and len(collided) < len(got)
    assert len({len(e.frames) for e in got.values()}) > 1  # the batch shrank as runs ended
    for episode in collided:
        assert log_bytes(episode) == log_bytes(run_episode(episode.spec))


def controllers(run):
    return [run.driver.controller]


def npcs(run):
    return run.world.npcs


FAULTS = {  # where one run breaks: in its ADS (control) or in its world (an NPC driver model)
    "ads": (controllers, PurePursuitController, "control",
            lambda self, plan, ego: plan.t_s >= 1.0, RuntimeError("actuator fault")),
    "world": (npcs, Npc, "decide", lambda self, gap, v: self.clock_s >= 2.0,
              ZeroDivisionError("float division by zero")),
}


@pytest.mark.parametrize("where", sorted(FAULTS))
def test_a_run_that_raises_ends_alone(monkeypatch, where):
    parts, cls, method, when, error = FAULTS[where]
    specs = plan_uniform("highway-cut-in", 4, seed=8)
    bad = specs[1].seed
    start, real = runner.RunLoop.start, getattr(cls, method)

    def marked_start(self):
        start(self)
        for part in parts(self):
            part.broken = self.spec.seed == bad

    def flaky(self, *args):
        if getattr(self, "broken", False) and when(self, *args):
            raise error
        return real(self, *args)

    monkeypatch.setattr(runner.RunLoop, "start", marked_start)
    monkeypatch.setattr(cls, method, flaky)
    got = by_id(list(run_lockstep(specs, SHORT)))
    broken = got[specs[1].scenario_id]
    assert broken.outcome.status == STATUS_FAILED
    assert broken.outcome.reason == f"{type(error).__name__}: {error}"
    if where == "ads":
        assert len(broken.frames) == 20  # frames 0 … 19 recorded; it raised at t = 1.0 s
    for spec in (specs[0], *specs[2:]):
        assert got[spec.scenario_id].outcome.status == STATUS_OK
        assert log_bytes(got[spec.scenario_id]) == log_bytes(run_episode(spec, SHORT))


def test_chunks_keep_one_scenario_profile_and_world_per_batch():
    specs = (plan_uniform("highway-cut-in", 5, seed=1) + plan_uniform("highway-cut-in", 3, seed=1,
                                                                      ads="cautious")
             + plan_uniform("occluded-crossing", 2, seed=1))
    sizes = [[(s.scenario, s.ads) for s in c] for c in chunks(specs, 2)]
    assert [len(c) for c in sizes] == [2, 2, 1, 2, 1, 2]
    assert all(len(set(c)) == 1 for c in sizes)
    with pytest.raises(ValueError, match="at least 1 run"):
        list(chunks(specs, 0))
    # spread over workers: at most the size asked, every worker a batch
    assert [batch_size(n, 2) for n in (200, 100, 3, 1, 0)] == [64, 50, 2, 1, 1]


@pytest.mark.parametrize(("stage", "work_first"), [
    ("detect_batch", True), ("track_batch", False), ("predict_batch", True),
    ("plan_batch", False)])
def test_a_batched_stage_that_raises_is_redone_run_by_run(monkeypatch, stage, work_first):
    """On the fifth frame the batched stage raises (sensing and prediction after doing their
    work, sensing's draws included; tracking and planning, which keep state, before changing
    any): the
    stage is redone per run from where it started, and every log is unchanged."""
    real = getattr(stack, stage)
    calls = []

    def fails_once(*args):
        calls.append(1)
        if len(calls) == 5:
            if work_first:
                real(*args)
            raise MemoryError("out of memory")
        return real(*args)

    monkeypatch.setattr(stack, stage, fails_once)
    specs = plan_uniform("unprotected-intersection", 3, seed=2)
    for episode in run_lockstep(specs, SHORT):
        assert episode.outcome.status == STATUS_OK
        assert log_bytes(episode) == log_bytes(run_episode(episode.spec, SHORT))
    assert len(calls) > 5
