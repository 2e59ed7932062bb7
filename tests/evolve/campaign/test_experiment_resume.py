"""Campaigns side by side: the same records on local workers, killed or not, and on Dask."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import threading
import time

import pytest

from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import run_experiment
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse
from evoeye.store.feedback import read_feedback, read_rounds

SCENARIO = "unprotected-intersection"  # of the `seeded` data root (conftest.py)
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)
METHODS = ["uniform", "evoeye"]
BUDGET_S = 60.0  # a few rounds of one run each
EXPERIMENT = f"""
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import run_experiment
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec

root = DataRoot.resolve({{root!r}})
base = CampaignConfig({SCENARIO!r}, n_round=1, epochs=1,
                      splits=SplitSpec(seed=0, train_frac=0.5, val_frac=0.25))
run_experiment(root, [{SCENARIO!r}], base, strategies={METHODS!r}, seeds=[0],
               budget_s={BUDGET_S}, controls=0, workers=2, progress=lambda line: None)
"""


def experiment(root: DataRoot, workers: int = 1, dask_address: str | None = None) -> list[str]:
    """Run the experiment; the progress lines it printed."""
    lines: list[str] = []
    base = CampaignConfig(SCENARIO, n_round=1, epochs=1, splits=SPLITS)
    run_experiment(root, [SCENARIO], base, strategies=METHODS, seeds=[0], budget_s=BUDGET_S,
                   controls=0, workers=workers, dask_address=dask_address,
                   progress=lines.append)
    return lines


def records(root: DataRoot) -> dict:
    """Everything the experiment's campaigns left behind that must not depend on a kill."""
    rounds = [r for r in read_rounds(root) if r.campaign_id.startswith("evo-")]
    fb = read_feedback(root)
    committed = Warehouse(root).sql(
        "SELECT scenario_id, count(*) AS n FROM scenarios GROUP BY 1 ORDER BY 1").to_pylist()
    return {
        "rounds": [(r.campaign_id, r.round, r.monitor_version, list(r.scenario_ids),
                    r.n_records, r.simulated_s, r.metrics) for r in rounds],
        "feedback": sorted(zip(*(fb.column(c).to_pylist() for c in (
            "monitor_version", "feedback_mode", "scenario_id", "feedback")), strict=True)),
        "logs": sorted(root.relative(p) for p in root.runs.rglob("*.mcap")),
        "committed": committed,
    }


@pytest.fixture(scope="module")
def uninterrupted(seeded, tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The records of the experiment run without a break, one campaign after the other."""
    clean = DataRoot.resolve(tmp_path_factory.mktemp("clean") / "data")
    shutil.copytree(seeded[0].path, clean.path)
    experiment(clean, workers=1)
    return records(clean)


def test_a_killed_two_worker_experiment_resumes_to_the_same_records(root_copy,
                                                                    uninterrupted) -> None:
    expected = uninterrupted
    per_campaign = {}
    for campaign_id, *_rest in expected["rounds"]:
        per_campaign[campaign_id] = per_campaign.get(campaign_id, 0) + 1
    assert len(per_campaign) == 2 and min(per_campaign.values()) >= 3  # rounds 0, 1, 2, …
    assert all(row["n"] == 1 for row in expected["committed"])

    root = root_copy("killed")
    proc = subprocess.Popen([sys.executable, "-c", EXPERIMENT.format(root=str(root.path))],
                            start_new_session=True, env=os.environ.copy())
    try:  # killed, with its workers, once some campaign has finished its first round
        deadline = time.monotonic() + 600
        while not any(r.round >= 1 for r in read_rounds(root)):
            assert proc.poll() is None, "the experiment ended before it could be killed"
            assert time.monotonic() < deadline, "no round finished in 10 minutes"
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    cut = records(root)
    assert cut["rounds"] != expected["rounds"]  # it was stopped part-way
    experiment(root, workers=2)
    assert records(root) == expected


def test_a_dask_cluster_runs_the_campaigns_to_the_same_records(root_copy, uninterrupted) -> None:
    from distributed import Client, LocalCluster

    root = root_copy("dask")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,  # Dask's default
                      dashboard_address=None,  # worker environment, and our preload
                      preload=["evoeye.evolve.campaign.workers"]) as cluster:
        with Client(cluster.scheduler_address) as client:  # loaded before any campaign
            loaded = client.run(lambda: sorted({"torch", "highway_env", "duckdb"}
                                               & set(sys.modules)))
        lines = experiment(root, dask_address=cluster.scheduler_address)
    assert list(loaded.values()) == [["duckdb", "highway_env", "torch"]] * 2
    assert records(root) == uninterrupted
    notes = [line for line in lines if line.startswith("note:")]
    assert len(notes) == 1 and "2 of 2 Dask workers" in notes[0]  # told, once


def test_a_malloc_note_only_for_workers_with_a_fixed_trim_and_no_mmap_threshold() -> None:
    from evoeye.evolve.campaign.workers import malloc_note

    assert malloc_note({"a": (None, None), "b": ("134217728", "134217728")}) is None
    note = malloc_note({"a": ("65536", None), "b": (None, None), "c": ("65536", "1")})
    assert note is not None and "1 of 3 Dask workers" in note and "=65536" in note


def test_a_lost_dask_worker_is_reported_and_changes_no_record(root_copy, uninterrupted) -> None:
    from distributed import Client, LocalCluster

    root = root_copy("lost")
    lines: list[str] = []
    base = CampaignConfig(SCENARIO, n_round=1, epochs=1, splits=SPLITS)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, \
            Client(cluster.scheduler_address) as client:
        run = threading.Thread(target=run_experiment, args=(root, [SCENARIO], base), kwargs=dict(
            strategies=METHODS, seeds=[0], budget_s=BUDGET_S, controls=0,
            dask_address=cluster.scheduler_address, progress=lines.append))
        run.start()
        deadline = time.monotonic() + 600
        while not any(" round 1:" in line for line in lines):
            assert run.is_alive() and time.monotonic() < deadline
            time.sleep(0.05)
        victim = next(w for w, keys in client.processing().items() if keys)
        os.kill(client.run(os.getpid, workers=[victim])[victim], signal.SIGKILL)
        run.join(600)
    moved = [line for line in lines if line.startswith(f"Dask worker {victim} left")]
    assert len(moved) == 1 and "move to another worker" in moved[0], lines
    assert "results are unaffected" in moved[0]
    for method in METHODS:  # every round's line, the moved campaign's included
        assert any(f"{method} seed 0 round 1:" in line for line in lines), (method, lines)
    assert records(root) == uninterrupted
