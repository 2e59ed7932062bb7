"""Prefect flows: thin wrappers that add retries, caching and fan-out to evoeye's functions."""

import os

# A temporary Prefect server (the demo's, the tests') sends anonymous usage data at start-up; on
# an offline machine that only logs errors. Off unless the user sets it.
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
