"""The root Typer application; command modules register themselves on it."""

import typer

app = typer.Typer(
    no_args_is_help=True,
    add_completion=False,
    help="evoeye: self-evolving runtime monitoring of autonomous driving systems.",
)
