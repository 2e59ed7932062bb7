"""`evoeye --help` and every `evoeye <command> --help` start without the heavy libraries."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("torch", "sklearn", "highway_env", "pandas", "duckdb", "pyarrow", "numpy", "scipy",
         "prefect", "polars", "onnx", "mcap", "rosbags")
PROBE = """
import json, sys
from evoeye.cli import app
try:
    app(sys.argv[1:], prog_name="evoeye")
except SystemExit:
    pass
print(json.dumps(sorted({m.split(".")[0] for m in sys.modules})))
"""


def _modules_after(*args: str) -> set[str]:
    done = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True, text=True,
                          check=True)
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


def _commands() -> list[list[str]]:
    from typer.main import get_command

    from evoeye.cli import app

    group = get_command(app)
    out = []
    for name, cmd in group.commands.items():
        subs = getattr(cmd, "commands", None)
        out += [[name, sub] for sub in subs] if subs else [[name]]
    return out


def test_every_command_is_listed() -> None:
    names = {" ".join(c) for c in _commands()}
    assert {"simulate", "ingest", "sql", "warehouse stats", "train", "evolve"} <= names


@pytest.mark.parametrize("command", [[], *_commands()], ids=lambda c: " ".join(c) or "evoeye")
def test_help_imports_no_heavy_module(command: list[str]) -> None:
    loaded = _modules_after(*command, "--help")
    assert "typer" in loaded  # the probe did run the app
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))
