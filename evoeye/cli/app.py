"""The root Typer application; command modules register themselves on it.

Adding a command is a one-place change: write `evoeye/cli/<name>.py` whose functions register on
the shared `app` (`@app.command("name")`, or `app.add_typer(sub, name=…)` for a group) and add
`<name>` to `COMMAND_MODULES` in `evoeye/cli/__init__.py`. Keep that module's top-level imports
light — typer, rich, the standard library, `evoeye.paths`, `evoeye.cli.*` — and import numpy,
torch, duckdb, pyarrow, pandas, sklearn, highway_env and the evoeye stages inside the command
function: `evoeye --help` imports every command module, and must start about as fast as
typer itself (tests/cli/test_startup.py checks that no heavy module is imported).

Errors: raise `evoeye.cli.errors.UserError(message, hint)` for a mistake the user can fix, or let
an exception listed in `errors.KNOWN_ERRORS` propagate; the group below prints it as one line
and exits with `ExitCode.USER_ERROR`. `evoeye --debug CMD` shows the traceback instead.
"""

from __future__ import annotations

import os
from typing import Annotated, Any

import typer
from typer.core import TyperGroup
from typer.exceptions import TyperException

from evoeye.cli.errors import EXIT_CODES_HELP, ExitCode, explain

DEBUG_KEY = "evoeye.debug"


def debugging(ctx: typer.Context) -> bool:
    """Whether tracebacks are wanted (--debug or EVOEYE_DEBUG=1)."""
    return bool(ctx.meta.get(DEBUG_KEY)) or os.environ.get("EVOEYE_DEBUG", "") not in ("", "0")


def report_user_error(exc: BaseException) -> bool:
    """Print a known user error as one line plus its hint on stderr; False if it is not one."""
    known = explain(exc)
    if known is None:
        return False
    from rich.console import Console
    from rich.markup import escape

    err = Console(stderr=True, soft_wrap=True)
    err.print(f"[red]error:[/] {escape(known.message)}")
    if known.hint:
        err.print(f"[dim]hint:[/] {escape(known.hint)}")
    return True


def report_interrupt(exc: KeyboardInterrupt) -> None:
    """One line on stderr: what an interrupted command kept (its own words, if it has some)."""
    from rich.console import Console
    from rich.markup import escape

    kept = str(exc) or ("every file is written whole or not at all: run the same command "
                        "again to resume")
    Console(stderr=True, soft_wrap=True).print(f"[yellow]interrupted:[/] {escape(kept)}")


class EvoeyeGroup(TyperGroup):
    """The root command group: turns known user errors into one line and an exit code."""

    def invoke(self, ctx: typer.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (typer.Exit, typer.Abort, TyperException):  # exits and usage errors: as they are
            raise
        except KeyboardInterrupt as exc:  # Ctrl-C: say what was kept, exit 130
            report_interrupt(exc)
            raise typer.Exit(ExitCode.INTERRUPTED) from None
        except Exception as exc:
            if debugging(ctx) or not report_user_error(exc):
                raise
            raise typer.Exit(ExitCode.USER_ERROR) from None


app = typer.Typer(
    cls=EvoeyeGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,  # plain help: rich's help formatter costs ~0.15 s more at start-up
    help="evoeye: self-evolving runtime monitoring of autonomous driving systems.",
    epilog=EXIT_CODES_HELP,
)


@app.callback()
def _root_options(
    ctx: typer.Context,
    debug: Annotated[bool, typer.Option(
        "--debug", help="Show the full traceback of any error.")] = False,
) -> None:
    ctx.meta[DEBUG_KEY] = debug


def exit_with(code: ExitCode) -> None:
    """End the command with `code` (nothing happens for OK)."""
    if code is not ExitCode.OK:
        raise typer.Exit(int(code))
