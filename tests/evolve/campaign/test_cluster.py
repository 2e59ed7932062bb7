"""Campaigns on a real Dask cluster: the preflight, a failure that stops the others, one writer
per campaign, and a cluster without workers."""

from __future__ import annotations

import os
import threading
import time

import pytest
from campaign_helpers import SCENARIO, SPLITS
from distributed import Client, LocalCluster

from evoeye.evolve.campaign import cluster as cluster_mod
from evoeye.evolve.campaign.cluster import ClusterError
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import campaign_jobs, plan_experiment
from evoeye.evolve.campaign.guard import CampaignBusyError, campaign_lease
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.workers import run_campaigns
from evoeye.paths import DataRoot
from evoeye.store.feedback import read_rounds

BASE = CampaignConfig(SCENARIO, n_round=1, epochs=1, splits=SPLITS)


def _jobs(root: DataRoot, budget_s: float = 600.0):
    plan = plan_experiment(root, [SCENARIO], BASE, strategies=["uniform", "evoeye"], seeds=[0],
                           budget_s=budget_s)
    return campaign_jobs(root, plan)


def _cluster(n: int = 2) -> LocalCluster:
    return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                        dashboard_address=None)


def _evolved(root: DataRoot) -> list:
    return [r for r in read_rounds(root) if r.round > 0]


def test_a_worker_that_cannot_see_the_root_is_named_before_any_campaign_starts(
        root_copy, tmp_path, monkeypatch) -> None:
    real = root_copy("real")
    view, elsewhere = tmp_path / "view", tmp_path / "elsewhere"
    view.mkdir()
    elsewhere.mkdir()
    (view / "data").symlink_to(real.path)
    monkeypatch.chdir(view)  # the client and the workers start here, where ./data is the root
    root = DataRoot.resolve("/proc/self/cwd/data")  # one path, each process's own view of it
    lines: list[str] = []
    with _cluster() as cluster, Client(cluster.scheduler_address) as client:
        blind = sorted(client.scheduler_info()["workers"])[0]
        client.run(os.chdir, str(elsewhere), workers=[blind])  # its ./data is no root
        t0 = time.monotonic()
        with pytest.raises(ClusterError) as err:
            run_campaigns(_jobs(root), dask_address=cluster.scheduler_address,
                          progress=lines.append)
        elapsed = time.monotonic() - t0
        assert not any(client.processing().values())  # no campaign runs anywhere
    message = str(err.value)
    assert f"Dask worker {blind} on " in message
    assert "cannot see /proc/self/cwd/data" in message and "\n" not in message
    assert elapsed < 30
    assert read_rounds(real) == []  # not even round 0: the preflight comes first


def test_a_failed_campaign_stops_the_others_and_a_running_one_is_never_run_twice(
        root_copy) -> None:
    root = root_copy("stop")
    jobs = _jobs(root)
    busy, other = (Campaign(root, j.config) for j in (jobs[1], jobs[0]))
    lines: list[str] = []
    with _cluster() as cluster:
        # as if a first run of it still held it
        with campaign_lease(root, busy.campaign_id), pytest.raises(ClusterError,
                                                                     match="already running"):
            run_campaigns(jobs, dask_address=cluster.scheduler_address, progress=lines.append)
        stopped = len(read_rounds(root, other.campaign_id))
        with campaign_lease(root, other.campaign_id):
            pass  # free: the other campaign stopped, its worker holds nothing
        time.sleep(2)
        assert len(read_rounds(root, other.campaign_id)) == stopped
    assert not other.finished()  # stopped long before its 600 s budget
    assert "stopping 1 unfinished campaign(s) on the cluster" in lines, lines
    with campaign_lease(root, busy.campaign_id), pytest.raises(CampaignBusyError,
                                                                 match="pid"):
        busy.run(max_rounds=1)  # the same process again: refused too, naming the holder


def test_a_cluster_without_workers_fails_after_the_timeout(root_copy, monkeypatch) -> None:
    monkeypatch.setattr(cluster_mod, "NO_WORKERS_TIMEOUT_S", 2.0)
    root = root_copy("empty")
    with _cluster(0) as cluster, pytest.raises(ClusterError, match="no Dask worker joined"):
        run_campaigns(_jobs(root), dask_address=cluster.scheduler_address,
                      progress=lambda line: None)
    assert _evolved(root) == []


def test_a_failed_campaign_stops_the_local_workers_too(root_copy) -> None:
    root = root_copy("local")
    jobs = _jobs(root)
    busy, other = (Campaign(root, j.config) for j in (jobs[1], jobs[0]))
    with campaign_lease(root, busy.campaign_id), \
            pytest.raises(CampaignBusyError, match="already running"):
        run_campaigns(jobs, workers=2, progress=lambda line: None)
    with campaign_lease(root, other.campaign_id):
        pass  # its worker process was stopped with the failure
    assert not other.finished()


def test_a_loopback_prefect_api_is_noted_for_a_cluster() -> None:
    from evoeye.evolve.campaign.cluster import loopback_api_note

    note = loopback_api_note("http://127.0.0.1:4200/api")
    assert note is not None and "prefect server start --host 0.0.0.0" in note
    assert loopback_api_note("http://localhost:4200/api") is not None
    assert loopback_api_note("http://192.0.2.2:4200/api") is None
    assert loopback_api_note(None) is None


def test_a_cluster_whose_workers_all_leave_fails_after_the_timeout(root_copy,
                                                                   monkeypatch) -> None:
    monkeypatch.setattr(cluster_mod, "NO_WORKERS_TIMEOUT_S", 3.0)
    root = root_copy("all-gone")
    lines: list[str] = []
    failed: list[BaseException] = []

    def experiment(address: str) -> None:
        try:
            run_campaigns(_jobs(root, budget_s=200.0), dask_address=address,
                          progress=lines.append)
        except BaseException as exc:  # noqa: BLE001 - handed to the test's thread
            failed.append(exc)

    with _cluster(1) as cluster, Client(cluster.scheduler_address) as client:
        run = threading.Thread(target=experiment, args=(cluster.scheduler_address,))
        run.start()
        deadline = time.monotonic() + 300
        while not any(" round 1:" in line for line in lines):
            assert run.is_alive() and time.monotonic() < deadline, lines
            time.sleep(0.05)
        client.retire_workers(close_workers=True, remove=True)  # the only worker, for good
        cluster.scale(0)
        run.join(120)
    assert not run.is_alive()
    assert len(failed) == 1 and isinstance(failed[0], ClusterError), failed
    assert "no Dask worker left" in str(failed[0]) and "for 3 s; unfinished" in str(failed[0])
    assert any(line.startswith("Dask worker") and "left the cluster" in line for line in lines)


def test_the_worker_view_names_a_version_a_monitor_or_a_root_it_lacks(seeded, tmp_path) -> None:
    from evoeye import __version__
    from evoeye.evolve.campaign.cluster import worker_view

    root, g0 = seeded
    assert worker_view(str(root.path), [g0], __version__)[1] == ""
    assert worker_view(str(root.path), [g0], "0.0.1")[1] == (
        f"runs evoeye {__version__}, the client 0.0.1")
    assert worker_view(str(root.path), ["fusion-elsewhere"], __version__)[1] == (
        f"cannot see {root.monitors / 'fusion-elsewhere'}")
    assert worker_view(str(tmp_path / "none"), [g0], __version__)[1] == (
        f"cannot see {tmp_path / 'none'}")
