"""Supervised runs do not depend on what else runs in the process: two runs supervised at once
in threads (Prefect's default task runner), and a run supervised after others in the same
thread, give the records a run supervised alone gives."""

from __future__ import annotations

import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path

import pytest

from evoeye.evaluation.supervision.batch import plan_supervision
from evoeye.evaluation.supervision.settings import Settings
from evoeye.evaluation.supervision.sweep import RunJob, supervise_run
from evoeye.evaluation.supervision.triggers import calibrate_triggers, oracle_trigger

# its module fixtures are built once only if its tests share a worker (pytest-xdist
# --dist loadgroup); spread over two, each worker builds them again
pytestmark = pytest.mark.xdist_group("supervision-concurrent")

TRIGGERS = [("baseline", "ttc"), ("baseline", "rss")]


@pytest.fixture(scope="module")
def settings(sup) -> Settings:
    """A FusionMonitor (ONNX Runtime, thresholds on its logits), TTC, RSS and the oracle."""
    from evoeye.monitor import train_monitor

    version = train_monitor(sup.root, sup.scenario, seed=0, splits=sup.splits, epochs=1)
    triggers = calibrate_triggers(sup.root, sup.scenario, [("version", version), *TRIGGERS],
                                  sup.splits, sup.fprs, 3.0)
    assert [t.scale for t in triggers] == ["logit", "score", "score"]
    return Settings(sup.scenario, sup.batch, (*triggers, oracle_trigger()), splits=sup.splits,
                    logs="none")


def _jobs(sup, settings: Settings, folder: Path) -> list[RunJob]:
    """The batch's two colliding runs (1 and 2) and a safe one (3)."""
    runs = plan_supervision(sup.root, replace(settings, batch=sup.batch)).runs[1:]
    return [RunJob(str(sup.root.path), str(folder), settings, spec, meta) for spec, meta in runs]


@pytest.fixture(scope="module")
def alone(sup, settings: Settings, tmp_path_factory) -> dict[str, dict]:
    """Each run's record, supervised one after the other in this thread."""
    folder = tmp_path_factory.mktemp("alone")
    return {j.spec.scenario_id: supervise_run(j) for j in _jobs(sup, settings, folder)}


def test_two_runs_supervised_at_once_in_threads_reproduce_their_twins(
        sup, settings: Settings, alone: dict[str, dict], tmp_path: Path) -> None:
    jobs = _jobs(sup, settings, tmp_path)
    was = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # the threads interleave at every few bytecodes
    try:
        with ThreadPoolExecutor(max_workers=2) as pool:
            records = list(pool.map(supervise_run, jobs))  # a ReproductionError propagates
    finally:
        sys.setswitchinterval(was)
    assert len(records) == 3 and any(r["triggers"]["ttc"]["sims"] for r in records)
    assert {r["scenario_id"]: r for r in records} == alone


def test_a_run_supervised_after_others_in_the_same_thread_is_the_same(
        sup, settings: Settings, alone: dict[str, dict], tmp_path: Path) -> None:
    jobs = _jobs(sup, settings, tmp_path)
    for job in [*jobs[1:], jobs[0]]:  # its scorers were last used on other runs
        assert supervise_run(job) == alone[job.spec.scenario_id]
