"""One Prefect API per flow run: a configured one is used as it is; otherwise one temporary
server serves the flow run and every worker process it starts."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from flows.api import API_URL_VAR, one_api_server, shared_with_workers


def test_a_configured_api_is_used_and_no_server_started(monkeypatch) -> None:
    from prefect.server.api.server import SubprocessASGIServer

    monkeypatch.setenv(API_URL_VAR, "http://127.0.0.1:9/api")
    monkeypatch.setattr(SubprocessASGIServer, "start",
                        lambda *a, **k: pytest.fail("a server was started"))
    with one_api_server() as url:
        assert url == "http://127.0.0.1:9/api"
    with shared_with_workers() as url:
        assert url == "http://127.0.0.1:9/api"
    assert os.environ[API_URL_VAR] == "http://127.0.0.1:9/api"  # left as it was


@pytest.mark.slow  # starts a temporary Prefect server: ≈ 15-20 s, more under load
def test_a_flow_run_and_its_workers_share_one_temporary_server(tmp_path) -> None:
    env = {k: v for k, v in os.environ.items() if k != API_URL_VAR}
    env["PREFECT_HOME"] = str(tmp_path / "prefect")
    done = subprocess.run(
        [sys.executable, "-m", "flows.simulate", "--scenario", "highway-cut-in", "--n", "3",
         "--workers", "2", "--root", str(tmp_path / "data")],
        capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    log = done.stdout + done.stderr
    assert log.count("Starting temporary server") == 1, log[-3000:]
    assert "Error logging to API" not in log, log[-3000:]  # its logs sent before it stopped
    assert "simulate-highway-cut-in-uniform-seed0-n3" in log  # the flow run's name
    assert len(list((tmp_path / "data").rglob("*.mcap"))) == 3
