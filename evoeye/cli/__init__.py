"""The `evoeye` command: each module below registers its commands on the shared app."""

from evoeye.cli import (  # noqa: F401
    audit,
    demo,
    evaluate,
    evolve,
    explain,
    monitor,
    simulate,
    warehouse,
)
from evoeye.cli.app import app

__all__ = ["app"]
