"""The `evoeye` command: each module below registers its commands on the shared app."""

from evoeye.cli import demo, simulate, warehouse  # noqa: F401  (registers commands)
from evoeye.cli.app import app

__all__ = ["app"]
