"""One Prefect API per flow run: the configured one, or one temporary server shared by all.

With no PREFECT_API_URL, Prefect starts a temporary API server in every process that needs one,
and a task runner's worker processes are such processes: a batch on two local workers started
three servers (≈ 5 s of CPU each). `one_api_server` starts the temporary server once, in the
process that runs the flow, and exports its address in the environment, which the workers
inherit; `shared_with_workers` does the same from inside a running flow, for flows called
from Python.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

API_URL_VAR = "PREFECT_API_URL"


def configured_api_url() -> str | None:
    """The API this process is configured for (environment or Prefect profile), if any."""
    from prefect.settings import PREFECT_API_URL

    return os.environ.get(API_URL_VAR) or PREFECT_API_URL.value() or None


def _export(url: str) -> Iterator[str]:
    """Set PREFECT_API_URL for this process and its children while the context lasts."""
    from prefect.settings import PREFECT_API_URL, temporary_settings

    before = os.environ.get(API_URL_VAR)
    os.environ[API_URL_VAR] = url
    try:
        with temporary_settings({PREFECT_API_URL: url}):
            yield url
    finally:
        if before is None:
            os.environ.pop(API_URL_VAR, None)
        else:
            os.environ[API_URL_VAR] = before


@contextmanager
def one_api_server() -> Iterator[str]:
    """The configured API, or a temporary server started here and stopped on exit, exported
    so that every process started inside the context uses it; yields its URL."""
    url = configured_api_url()
    if url:
        yield url
        return
    from prefect.server.api.server import SubprocessASGIServer

    server = SubprocessASGIServer()
    server.start()
    try:
        yield from _export(server.api_url)
    finally:
        _send_queued_logs()
        server.stop()


def _send_queued_logs(timeout_s: float = 10.0) -> None:
    """Send the logs Prefect still queues for the API (it sends them in batches, in the
    background) while the temporary server runs: left queued, they were sent at exit, to a
    stopped server, and the run ended on "--- Error logging to API --- All connection attempts
    failed" under its summary."""
    from prefect.logging.handlers import APILogWorker

    APILogWorker.drain_all(timeout=timeout_s)


@contextmanager
def shared_with_workers() -> Iterator[str | None]:
    """Inside a flow run: while the context lasts, the processes it starts (a process pool's,
    a Dask cluster's through the serialised settings) use the API this process talks to — the
    temporary server Prefect started for it when none was configured; yields its URL."""
    url = configured_api_url()
    if url:
        yield url
        return
    from prefect.server.api.server import SubprocessASGIServer

    server = SubprocessASGIServer()  # the instance this process's client started
    if not server.running:
        yield None
        return
    yield from _export(server.api_url)
