"""`python -m flows.<name> [--field value …]`: run a flow from the shell, with `--help`.

The options are the fields of the flow's pydantic parameters (`--budget-s 600` sets `budget_s`);
what is not given keeps its default, and the model validates the whole before anything runs.
The flow's result is printed as JSON.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from flows.api import one_api_server

API_NOTE = (
    "Prefect: with no PREFECT_API_URL a flow run first starts one temporary API server, shared "
    "by its worker processes (≈ 5-20 s, longer on a busy machine; timeout "
    "PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS). To skip that, run `prefect server "
    "start` once and set PREFECT_API_URL=http://127.0.0.1:4200/api."
)


def _inner(annotation: Any) -> Any:
    """`X | None` → X."""
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        return args[0] if len(args) == 1 else str
    return annotation


def _help(field: Any, about: str | None = None, default: Any = argparse.SUPPRESS) -> str:
    extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
    choices = f"one of {', '.join(map(str, extra['enum']))}; " if "enum" in extra else ""
    if default is argparse.SUPPRESS:
        default = field.get_default(call_default_factory=True)
    about = about or field.description
    return f"{about + ' ' if about else ''}({choices}default: {default})"


@dataclasses.dataclass(frozen=True)
class Override:
    """How one field shows on a command line other than the model says: its help, its
    default (applied, and shown by --help) and other flags for it."""

    help: str | None = None
    default: Any = argparse.SUPPRESS
    aliases: tuple[str, ...] = ()


def say_what_we_wait_for() -> None:
    """Tell the user, before a flow runs, that a temporary Prefect server starts first."""
    if not os.environ.get("PREFECT_API_URL"):
        timeout = os.environ.get("PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS", "20")
        print(f"starting Prefect's temporary API server first (≈ 5-20 s, up to {timeout} s on a "
              "busy machine); set PREFECT_API_URL to use a running `prefect server start` "
              "instead", file=sys.stderr, flush=True)


def _plain(value: Any) -> Any:
    return dataclasses.asdict(value) if dataclasses.is_dataclass(value) else str(value)


def parser_for(params: type[BaseModel], description: str | None,
               overrides: Mapping[str, Override] | None = None) -> argparse.ArgumentParser:
    """An argparse parser with one option per field of `params` (absent ones stay absent,
    unless `overrides` gives them a default)."""
    ap = argparse.ArgumentParser(prog=f"python -m flows.{Path(sys.argv[0]).stem}",
                                 description=description, epilog=API_NOTE,
                                 argument_default=argparse.SUPPRESS,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    for name, field in params.model_fields.items():
        how = (overrides or {}).get(name, Override())
        flags = ["--" + name.replace("_", "-"), *how.aliases]
        kind = _inner(field.annotation)
        common = {"dest": name, "help": _help(field, how.help, how.default),
                  "default": how.default}
        if kind is bool:
            ap.add_argument(*flags, action=argparse.BooleanOptionalAction, **common)
        elif typing.get_origin(kind) is list:
            ap.add_argument(*flags, nargs="+", metavar="VALUE", **common)
        else:
            ap.add_argument(*flags, metavar=getattr(kind, "__name__", "VALUE").upper(),
                            **common)
    return ap


def run_from_command_line(params: type[BaseModel], run: Callable[[Any], Any],
                          description: str | None, argv: Sequence[str] | None = None) -> Any:
    """Parse argv into `params`, run the flow with them, print its result as JSON."""
    ap = parser_for(params, description)
    given = vars(ap.parse_args(argv))
    try:
        chosen = params(**given)
    except (ValidationError, ValueError) as exc:
        ap.error(str(exc))
    say_what_we_wait_for()
    with one_api_server():  # one for the flow run and every worker process it starts
        result = run(chosen)
    print(json.dumps(result, default=_plain, indent=2))
    return result
