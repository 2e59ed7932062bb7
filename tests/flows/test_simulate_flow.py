"""The simulate flow through Prefect: local processes by default, a Dask cluster on request."""

from __future__ import annotations

import pytest
from distributed import LocalCluster
from pydantic import ValidationError

from evoeye.batch import plan_uniform, run_batch
from evoeye.log import read_run
from evoeye.paths import DataRoot
from flows import simulate as simulate_mod
from flows.runners import cluster_threads
from flows.simulate import SimulateParams, simulate_batch_flow


def test_simulate_flow_writes_one_log_per_run_and_reruns_skip(tmp_path, latest_artifact,
                                                              flow_run_names):
    params = SimulateParams(scenario="unprotected-intersection", n=2, seed=4,
                            root=str(tmp_path), workers=2)
    results = simulate_batch_flow(params)
    assert len(results) == 2 and all(r.status == "ok" for r in results)
    for r in results:
        assert read_run(r.path, topics=()).metadata["scenario_id"] == r.scenario_id
    again = simulate_batch_flow(params)
    assert all(r.skipped for r in again)
    assert sorted(r.path for r in again) == sorted(r.path for r in results)
    name = "simulate-unprotected-intersection-uniform-seed4-n2"
    assert flow_run_names(name) == [name, name]  # the run and the re-run
    artifact = latest_artifact("evoeye-simulate")  # the re-run's
    assert "# Simulated: unprotected-intersection" in artifact
    assert "| Runs | Collisions | Failed | Skipped |" in artifact


def test_simulate_flow_on_a_two_worker_dask_cluster(prefect_server, tmp_path):
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        params = SimulateParams(scenario="highway-cut-in", n=3, seed=9,
                                root=str(tmp_path / "dask"), dask_address=cluster.scheduler_address)
        results = simulate_batch_flow(params)  # two tasks: runs stepped together, 2 and 1
    assert len(results) == 3 and all(r.status == "ok" for r in results)
    one = DataRoot.resolve(tmp_path / "one")  # the same runs, one at a time, in this process
    run_batch(plan_uniform("highway-cut-in", 3, 9), one)
    dask_logs = sorted((tmp_path / "dask").rglob("*.mcap"))
    assert [p.name for p in dask_logs] == [p.name for p in sorted(one.path.rglob("*.mcap"))]
    assert [p.read_bytes() for p in dask_logs] == [
        p.read_bytes() for p in sorted(one.path.rglob("*.mcap"))]


def test_a_dask_fan_out_has_a_chunk_for_every_thread_of_the_cluster(prefect_server, tmp_path,
                                                                     monkeypatch):
    sizes = []
    real = simulate_mod.chunks

    def chunked(specs, size):  # the fan-out's chunks, as the flow cuts them
        sizes.extend(len(c) for c in real(specs, size))
        return real(specs, size)

    monkeypatch.setattr(simulate_mod, "chunks", chunked)
    with LocalCluster(n_workers=3, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        assert cluster_threads(cluster.scheduler_address) == 3
        params = SimulateParams(scenario="highway-cut-in", n=6, seed=2, workers=1,
                                root=str(tmp_path), dask_address=cluster.scheduler_address)
        results = simulate_batch_flow(params)
    assert len(results) == 6 and sorted(sizes) == [2, 2, 2]  # not one chunk for `workers` 1


def test_bad_parameters_are_refused_before_anything_runs():
    with pytest.raises(ValidationError, match="roundabout"):
        SimulateParams(scenario="roundabout")
    with pytest.raises(ValidationError, match="n"):
        SimulateParams(n=0)


def test_simulate_flow_can_ingest_its_batch(prefect_server, tmp_path):
    from evoeye.store import Warehouse

    params = SimulateParams(scenario="highway-cut-in", n=2, seed=5, root=str(tmp_path),
                            workers=1, ingest=True)
    results = simulate_batch_flow(params)
    ids = Warehouse(DataRoot.resolve(tmp_path)).sql(
        "SELECT scenario_id FROM scenarios ORDER BY scenario_id").column("scenario_id")
    assert ids.to_pylist() == sorted(r.scenario_id for r in results)
