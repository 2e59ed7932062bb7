"""Prefect flows: thin wrappers that add retries, caching and fan-out to evoeye's functions."""

import os

# A temporary Prefect server (the demo's, the tests') sends anonymous usage data at start-up; on
# an offline machine that only logs errors. Off unless the user sets it.
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")

# With no PREFECT_API_URL, a flow run starts a temporary API server, which Prefect gives 20 s by
# default: too little on a busy machine (it takes ≈ 15-20 s idle). Give it generous time; to skip
# the wait, start `prefect server start` once and point PREFECT_API_URL at it (README).
EPHEMERAL_STARTUP_TIMEOUT_S = 300
os.environ.setdefault("PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS",
                      str(EPHEMERAL_STARTUP_TIMEOUT_S))
