"""The `evoeye` command: each module in COMMAND_MODULES registers its commands on the shared app.

To add a command, see the module docstring of `evoeye.cli.app` (one new module, one name here).
"""

from importlib import import_module

from evoeye.cli.app import app

COMMAND_MODULES = (
    "simulate", "warehouse", "monitor", "monitors", "evaluate", "evolve", "demo", "audit",
    "explain", "results", "findings", "autoware", "apollo", "watch", "predictability", "supervise",
)

for _name in COMMAND_MODULES:
    import_module(f"evoeye.cli.{_name}")

__all__ = ["COMMAND_MODULES", "app"]
