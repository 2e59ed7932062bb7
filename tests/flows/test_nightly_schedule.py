"""The nightly deployment on a real `prefect server start`: its scheduler creates a flow run
of the deployment `python -m flows.deploy` registers, and the serve process runs it to a
campaign round (the session's test harness has no scheduler: it only runs flows by hand).

The server and the serve process are subprocesses with a Prefect home and API of their own;
this test process reaches that server through a client of its own, so the session's test
harness, which the other flow tests use, is never touched. Each subprocess is stopped, with
the processes it started, whatever the outcome.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from evoeye.store.feedback import read_rounds

pytestmark = pytest.mark.slow

SCENARIO = "unprotected-intersection"  # of the `fresh_root` data root (conftest)
EVERY_MINUTE = "* * * * *"
DEADLINE_S = 180.0  # from the serve process's start to a completed scheduled run
REPO = Path(__file__).resolve().parents[2]
PREFECT = str(Path(sys.executable).with_name("prefect"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def _started(args: list[str], env: dict[str, str], log: Path) -> Iterator[subprocess.Popen]:
    """`args` as a subprocess in a session of its own, its output in `log`; on exit it and
    every process it started are stopped (SIGTERM, then SIGKILL after 20 s)."""
    with log.open("wb") as out:
        proc = subprocess.Popen(args, env=env, cwd=REPO, stdout=out, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        yield proc
    finally:
        for sig, wait_s in ((signal.SIGTERM, 20), (signal.SIGKILL, 10)):
            try:
                os.killpg(proc.pid, sig)  # the session started above: its group id is its pid
            except ProcessLookupError:
                break
            try:
                proc.wait(wait_s)
                os.killpg(proc.pid, 0)  # children left in the group?
            except (subprocess.TimeoutExpired, ProcessLookupError):
                if proc.poll() is not None:
                    break


@dataclass
class Server:
    url: str
    env: dict[str, str]
    log: Path
    proc: subprocess.Popen

    def wait_ready(self, timeout_s: float = 150.0) -> None:
        import httpx

        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            assert self.proc.poll() is None, f"the server stopped:\n{self.log.read_text()}"
            try:
                if httpx.get(f"{self.url}/health", timeout=5).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(1)
        pytest.fail(f"no server after {timeout_s:.0f} s:\n{self.log.read_text()}")


@pytest.fixture
def real_server(tmp_path: Path) -> Iterator[Server]:
    """`prefect server start` on a free port with a Prefect home of its own, its scheduler
    looking every 5 s rather than 60 (started, not yet waited for: see `wait_ready`)."""
    url = f"http://127.0.0.1:{(port := _free_port())}/api"
    env = {k: v for k, v in os.environ.items() if not k.startswith("PREFECT_")}
    env |= {"PREFECT_HOME": str(tmp_path / "prefect-home"), "PREFECT_API_URL": url,
            "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
            "PREFECT_SERVER_SERVICES_SCHEDULER_LOOP_SECONDS": "5",
            "PREFECT_RUNNER_POLL_FREQUENCY": "2"}  # how often serve asks for runs due
    log = tmp_path / "server.log"
    args = [PREFECT, "server", "start", "--host", "127.0.0.1", "--port", str(port), "--no-ui"]
    with _started(args, env, log) as proc:
        yield Server(url, env, log, proc)


def _scheduled_runs(url: str) -> list:
    """The flow runs the server's scheduler created (not started by hand)."""
    from prefect.client.orchestration import SyncPrefectClient

    with SyncPrefectClient(url) as client:
        return [r for r in client.read_flow_runs() if r.auto_scheduled]


def test_the_scheduler_starts_a_nightly_run_that_adds_a_round(
        real_server: Server, fresh_root, tmp_path: Path) -> None:
    root, g0 = fresh_root  # built while the server starts
    real_server.wait_ready()
    args = [sys.executable, "-m", "flows.deploy", "--root", str(root.path),
            "--scenario", SCENARIO, "--strategy", "uniform", "--budget-s", "1000",
            "--monitor", g0, "--n-round", "3", "--epochs", "1", "--train-frac", "0.5",
            "--val-frac", "0.25", "--no-assess", "--max-rounds", "1", "--cron", EVERY_MINUTE]
    serve_log = tmp_path / "serve.log"
    started = time.monotonic()
    with _started(args, real_server.env, serve_log) as serve:
        done = []
        while not done and time.monotonic() - started < DEADLINE_S:
            assert serve.poll() is None, f"serve stopped:\n{serve_log.read_text()}"
            time.sleep(3)
            done = [r for r in _scheduled_runs(real_server.url) if r.state.is_completed()]
        took_s = time.monotonic() - started
        runs = _scheduled_runs(real_server.url)
    server_log = real_server.log.read_text()
    assert done, (f"no scheduled run completed in {DEADLINE_S:.0f} s: "
                  f"{[(r.name, r.state_name) for r in runs]}\n--- server\n{server_log}"
                  f"\n--- serve\n{serve_log.read_text()}")
    print(f"a scheduled run completed {took_s:.0f} s after serve started")
    assert done[0].name == f"evolve-{SCENARIO}-uniform-s0"
    assert done[0].parameters["budget_s"] == 1000 and done[0].parameters["max_rounds"] == 1
    # the round it added to the campaign (the root's only one), with N_round new runs
    rows = read_rounds(root)
    assert [r.round for r in rows][:2] == [0, 1] and len(rows[1].scenario_ids) == 3
    # no error on the server: SQLAlchemy 2.1 made its scheduler fail every few seconds
    assert "Traceback" not in server_log and "| ERROR" not in server_log, server_log
