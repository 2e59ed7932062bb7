"""Prefect flows: thin wrappers that add retries, caching and fan-out to evoeye's functions."""
