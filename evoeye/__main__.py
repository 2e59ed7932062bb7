"""`python -m evoeye …` runs the `evoeye` command."""

from evoeye.cli import app

app(prog_name="evoeye")
