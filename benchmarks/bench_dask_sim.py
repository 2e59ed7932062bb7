"""The simulate flow fanned out on a Dask cluster, as on several hosts: its scaling and its logs.

A LocalCluster of k one-thread worker processes stands in for k hosts. For each k of
`--workers`, the simulate flow (`flows.simulate`, `dask_address` set) runs the same `--n`
uniform runs into a fresh data root, each chunk of up to `--lockstep` runs stepped together
as one task. Wall seconds of the flow run (the cluster is started, and evoeye imported on
every worker, before the clock starts), the speed-up and efficiency against k = 1, and whether
every log is byte for byte the one `evoeye simulate` writes in this process
(`run_batch(lockstep=…)`). A temporary Prefect server (the test harness) serves the flow runs.

    python -m benchmarks.bench_dask_sim [--n 256] [--workers 1 2] [--scenario highway-cut-in]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from benchmarks.machine import describe
from evoeye.batch import plan_uniform, run_batch
from evoeye.paths import DataRoot


def logs(root: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(root.rglob("*.mcap"))}


def on_cluster(k: int, params: dict, root: Path) -> float:
    """Wall seconds of one simulate flow run on a fresh cluster of k worker processes."""
    from distributed import Client, LocalCluster

    from flows.simulate import SimulateParams, simulate_batch_flow

    with LocalCluster(n_workers=k, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        with Client(cluster.scheduler_address) as client:
            client.run(__import__, "evoeye.batch")  # every worker imports before the clock
        t0 = time.perf_counter()
        results = simulate_batch_flow(SimulateParams(**params, root=str(root),
                                                     dask_address=cluster.scheduler_address))
        wall = time.perf_counter() - t0
    if any(r.status != "ok" for r in results):
        raise RuntimeError(f"{sum(r.status != 'ok' for r in results)} runs did not simulate")
    return wall


def main() -> None:
    from prefect.testing.utilities import prefect_test_harness

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--scenario", default="highway-cut-in")
    ap.add_argument("--lockstep", type=int, default=64)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    a = ap.parse_args()
    print(describe())
    params = {"scenario": a.scenario, "n": a.n, "seed": a.seed, "lockstep": a.lockstep}
    with tempfile.TemporaryDirectory(prefix="bench-dask-sim-") as tmp, \
            prefect_test_harness(server_startup_timeout=120):
        local = DataRoot.resolve(Path(tmp) / "local")
        t0 = time.process_time()
        run_batch(plan_uniform(a.scenario, a.n, a.seed), local, workers=1, lockstep=a.lockstep)
        print(f"in this process: {time.process_time() - t0:.1f} CPU s for {a.n} runs")
        reference = logs(local.path)
        print("\n| Dask workers | wall s | speed-up | efficiency | logs equal to `evoeye "
              "simulate`'s |\n|---:|---:|---:|---:|---|")
        base = None
        for k in a.workers:
            root = Path(tmp) / f"dask-{k}"
            wall = on_cluster(k, params, root)
            base = base or wall * a.workers[0]
            speed = base / wall
            print(f"| {k} | {wall:.1f} | {speed:.2f}× | {100 * speed / k:.0f} % | "
                  f"{logs(root) == reference} |", flush=True)


if __name__ == "__main__":
    main()
