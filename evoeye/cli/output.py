"""Where commands print: stdout and stderr consoles, and tables that never cut a value.

When stdout is not a terminal (a pipe, a file, CI), rich would fit tables to 80 columns and cut
identifiers (`highway-cu…`); `out()` is then wide enough for any table, and every column folds
rather than truncating when a terminal is too narrow.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # rich's console and table modules load on first output, not for `--help`
    from rich.console import Console
    from rich.table import Table

PIPE_WIDTH = 4096  # characters; wider than any table evoeye prints


def out() -> Console:
    """A stdout console sized at call time (a terminal's width, else PIPE_WIDTH)."""
    from rich.console import Console

    console = Console()
    return console if console.is_terminal else Console(width=PIPE_WIDTH)


def err() -> Console:
    """A stderr console that never breaks a line: a message is one line in a file or a pipe
    (a terminal wraps it where it must, softly)."""
    from rich.console import Console

    return Console(stderr=True, soft_wrap=True)


def table(title: str | None, columns: list[str], *, left: tuple[str, ...] = (),
          show_header: bool = True) -> Table:
    """A table whose cells fold instead of being cut; `left` columns are left-justified, the
    rest right-justified (numbers)."""
    from rich.table import Table

    t = Table(title=title, show_header=show_header)
    for col in columns:
        t.add_column(col, justify="left" if col in left else "right", overflow="fold")
    return t


class StepBar:
    """A progress bar (tqdm, on stderr) for a library that reports steps through a
    `progress(message)` callback: each message starts a step (and ends the one before), and is
    printed above the bar; leaving the `with` block without an error ends the last step."""

    def __init__(self, desc: str, *, unit: str = "step", total: int | None = None) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, unit=unit)
        self.running = False

    def __call__(self, message: str) -> None:
        self.bar.write(message, file=sys.stderr)
        if self.running:
            self.bar.update(1)
        self.running = True

    def __enter__(self) -> StepBar:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        if exc_type is None and self.running:
            self.bar.update(1)
        self.bar.close()
