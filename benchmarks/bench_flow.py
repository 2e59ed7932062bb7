"""The Prefect flows against the command line, on the same simulate + ingest (target ≤ 1.2×).

Each path simulates `--n` runs of one logical scenario on `--workers` local processes into a
fresh data root, then ingests them, as two commands in fresh interpreters:

  cli        `evoeye simulate …` then `evoeye ingest …`
  flow       `python -m flows.simulate … --ingest`: one flow run (ingest a subflow run) against
             a running `prefect server start` (PREFECT_API_URL set), as a user with a server has it
  flows      `python -m flows.simulate …` then `python -m flows.ingest …`, the same server
  flow-tmp   `flow` with no PREFECT_API_URL: the command starts a temporary server first

CPU time is the commands' and their children's (workers, a temporary server), plus for `flow`
and `flows` what the running server spent answering them: its CPU during the commands minus
what it spends idle (its background services, measured while the `cli` path runs) over the
same wall time. On a shared machine CPU is the figure to compare (wall time is shown beside
it). Paths are interleaved, `--repeat` times; medians.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from contextlib import contextmanager
from pathlib import Path

import httpx
import psutil

from benchmarks.machine import describe

SERVER_PORT = 4277


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _tree_cpu_s(proc: psutil.Process) -> float:
    total = 0.0
    for p in [proc, *proc.children(recursive=True)]:
        try:
            t = p.cpu_times()
            total += t.user + t.system + t.children_user + t.children_system
        except psutil.NoSuchProcess:
            pass
    return total


PATHS = ("cli", "flow", "flows", "flow-tmp")
SERVED = ("flow", "flows")  # the paths run against the running server


def commands(path: str, root: Path, scenario: str, n: int, workers: int) -> list[list[str]]:
    py = sys.executable
    sim = ["--scenario", scenario, "--n", str(n), "--workers", str(workers), "--root", str(root)]
    ingest = ["ingest", "--root", str(root)]
    return {
        "cli": [[py, "-m", "evoeye", "simulate", *sim], [py, "-m", "evoeye", *ingest]],
        "flow": [[py, "-m", "flows.simulate", *sim, "--ingest"]],
        "flows": [[py, "-m", "flows.simulate", *sim], [py, "-m", "flows.ingest", *ingest[1:]]],
        "flow-tmp": [[py, "-m", "flows.simulate", *sim, "--ingest"]],
    }[path]


@contextmanager
def prefect_server(home: Path):
    """`prefect server start` on SERVER_PORT, its PREFECT_API_URL, and the process."""
    env = {**os.environ, "PREFECT_HOME": str(home), "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
           "PREFECT_UI_ENABLED": "false"}
    proc = subprocess.Popen([sys.executable, "-m", "prefect", "server", "start", "--port",
                             str(SERVER_PORT)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{SERVER_PORT}/api"
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline:
            try:
                if httpx.get(f"{url}/health", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.5)
        else:
            raise RuntimeError("prefect server start did not answer within 300 s")
        yield url, psutil.Process(proc.pid)
    finally:
        proc.terminate()
        proc.wait(30)


def measure(argvs: list[list[str]], env: dict[str, str],
            server_cpu: Callable[[], float]) -> tuple[float, float, float]:
    """(wall s, CPU s, the server's CPU s meanwhile) of the commands in turn."""
    t0, c0, s0 = time.perf_counter(), _children_cpu_s(), server_cpu()
    for argv in argvs:
        subprocess.run(argv, check=True, env=env, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0, _children_cpu_s() - c0, server_cpu() - s0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", default="highway-cut-in")
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="evoeye-bench-flow-"))
    base = {k: v for k, v in os.environ.items() if k != "PREFECT_API_URL"}
    base.update(PREFECT_HOME=str(work / "prefect-home"), PREFECT_SERVER_ANALYTICS_ENABLED="false")
    times: dict[str, list[tuple[float, float]]] = {p: [] for p in PATHS}
    idle: list[float] = []  # the server's CPU s per wall s while no flow uses it
    load = []
    try:
        with prefect_server(work / "server-home") as (url, server):
            for i in range(args.repeat):
                for path in times:
                    root = work / f"{path}-{i}"
                    env = {**base, "PREFECT_API_URL": url} if path in SERVED else base
                    argvs = commands(path, root, args.scenario, args.n, args.workers)
                    wall, cpu, served = measure(argvs, env, lambda: _tree_cpu_s(server))
                    if path == "cli":
                        idle.append(served / wall)
                    elif path in SERVED:  # what answering this path cost the server
                        cpu += max(0.0, served - statistics.median(idle) * wall)
                    times[path].append((wall, cpu))
                    load.append(os.getloadavg()[0])
                    shutil.rmtree(root, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    cli_wall = statistics.median(t for t, _ in times["cli"])
    cli_cpu = statistics.median(c for _, c in times["cli"])
    print(f"machine: {describe()}; load average {min(load):.1f}–{max(load):.1f}; "
          f"{args.scenario}, n = {args.n}, {args.workers} workers; median of {args.repeat}\n")
    print("| path | wall s | × cli | CPU s | × cli |")
    print("|---|---:|---:|---:|---:|")
    for path, ts in times.items():
        wall, cpu = statistics.median(t for t, _ in ts), statistics.median(c for _, c in ts)
        print(f"| {path} | {wall:.1f} | {wall / cli_wall:.2f} | {cpu:.1f} | {cpu / cli_cpu:.2f} |")


if __name__ == "__main__":
    main()
