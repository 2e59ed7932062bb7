"""The `evoeye` command: each module below registers its commands on the shared app."""

from evoeye.cli import audit, demo, evaluate, evolve, monitor, simulate, warehouse  # noqa: F401
from evoeye.cli.app import app

__all__ = ["app"]
