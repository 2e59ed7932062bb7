"""The README and docs/ match the code: every `evoeye …` command and option they show exists,
every `python -m …` module and its options exist, every exit code they state is one
`evoeye/cli/errors.py` defines, and every relative link leads to a file (and heading)."""

from __future__ import annotations

import contextlib
import io
import re
import runpy
import shlex
import sys
import warnings
from functools import cache
from pathlib import Path

import click
import pytest
import typer

from evoeye.cli import app
from evoeye.cli.errors import EXIT_CODES_HELP, ExitCode

REPO = Path(__file__).resolve().parents[1]
PAGES = sorted([REPO / "README.md", REPO / "CHANGELOG.md", REPO / "BENCHMARKS.md",
                *(REPO / "docs").rglob("*.md")])
SHELLS = {"", "bash", "sh", "shell", "console"}  # fenced blocks read as commands
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
SPAN = re.compile(r"(?<!`)`([^`\n]+(?:\n[^`\n]+)*)`(?!`)")  # an inline code span (may wrap)
SEPARATORS = {"&&", "||", ";", "|", "&"}
PLACEHOLDER = re.compile(r"^[A-Z][A-Z_]*$|^[…\.]+$")  # COMMAND, …, ...
OPTION = re.compile(r"^-{1,2}[a-zA-Z][\w-]*$")
SIGINT = 130  # a command stopped by Ctrl-C: 128 + SIGINT, the shell's code, not an ExitCode


def _tokens(text: str) -> list[str]:
    """Shell words of a snippet; brackets of optional parts, `=values` and `\\|` dropped."""
    text = text.replace("\\|", "|").replace("\\\n", " ")
    try:
        words = shlex.split(text, comments=True)
    except ValueError:  # an unclosed quote in a shortened example
        words = text.split()
    return [w.strip("[]()").split("=", 1)[0] if w.startswith(("-", "[-")) else w.strip("[]")
            for w in words]


def _commands(words: list[str]) -> list[list[str]]:
    """Each `evoeye …` or `python -m …` command in a list of shell words, as its words."""
    found: list[list[str]] = []
    current: list[str] | None = None
    for before, w in zip(["", *words], words, strict=False):
        if w in SEPARATORS:
            current = None
        elif current is not None:
            current.append(w)
        elif w == "evoeye" or w.endswith("/evoeye"):
            current = ["evoeye"]
            found.append(current)
        elif w == "-m" and re.search(r"(^|/)python3?$", before):
            current = ["python", "-m"]
            found.append(current)
    return [c for c in found if len(c) > 2 or c[0] == "evoeye"]


def page_commands(page: Path) -> list[tuple[str, list[str]]]:
    """(where, words) of every command a page shows: in shell blocks, and in inline code spans
    that start with `evoeye ` or `python -m `."""
    text = page.read_text(encoding="utf-8")
    out = []
    for lang, body in FENCE.findall(text):
        if lang in SHELLS:
            for line in body.replace("\\\n", " ").splitlines():
                out += [(f"{page.name}: {line.strip()}", c) for c in _commands(_tokens(line))]
    prose = FENCE.sub("", text)
    for span in SPAN.findall(prose):
        if span.startswith(("evoeye ", "python -m ")):
            out += [(f"{page.name}: `{span}`", c) for c in _commands(_tokens(span))]
    return out


ALL = [(where, words) for page in PAGES for where, words in page_commands(page)]
EVOEYE = [(where, words) for where, words in ALL if words[0] == "evoeye"]
MODULES = [(where, words) for where, words in ALL if words[0] == "python"]


def _options(command: click.Command) -> set[str]:
    return {o for p in command.params for o in (*p.opts, *p.secondary_opts)} | {"--help"}


@cache
def root_command() -> click.Command:
    return typer.main.get_command(app)


def resolve(words: list[str]) -> tuple[click.Command, list[str]] | None:
    """The click command the words name, and the words after it; None for a placeholder
    (`evoeye COMMAND …`). AssertionError naming an unknown command or group option."""
    command, rest = root_command(), words[1:]
    while hasattr(command, "commands"):  # a group: typer's, not necessarily click's class
        at, unknown = 0, []
        while at < len(rest) and OPTION.match(rest[at]):  # the group's own options, values
            param = next((p for p in command.params if rest[at] in p.opts), None)
            unknown += [] if param or rest[at] == "--help" else [rest[at]]
            at += 2 if param is not None and not getattr(param, "is_flag", True) else 1
        assert not unknown, f"no option {unknown} before the command in {words}"
        if at == len(rest) or PLACEHOLDER.match(rest[at]):
            return None
        assert rest[at] in command.commands, f"no command {rest[at]!r} in {words}"
        command, rest = command.commands[rest[at]], rest[at + 1:]
    return command, rest


def test_the_pages_show_commands() -> None:  # the parser finds what the checks are about
    names = {w[1] for _, w in EVOEYE if len(w) > 1}
    assert {"simulate", "ingest", "sql", "audit", "evaluate", "evolve", "results"} <= names
    assert any(w[2] == "flows.demo" for _, w in MODULES)


@pytest.mark.parametrize(("where", "words"), EVOEYE, ids=[w for w, _ in EVOEYE])
def test_every_evoeye_command_and_option_exists(where: str, words: list[str]) -> None:
    found = resolve(words)
    if found is None:
        return
    command, rest = found
    unknown = [w for w in rest if OPTION.match(w) and w not in _options(command)]
    assert not unknown, f"{where}: `{command.name}` has no option {unknown}"


@cache
def module_options(module: str) -> set[str]:
    """The options `python -m <module> --help` lists (the module run as it would be, stopped by
    argparse's --help before it does anything)."""
    stdout, argv, path = io.StringIO(), sys.argv, sys.path
    sys.argv, sys.path = [module, "--help"], [str(REPO), *sys.path]  # benchmarks/ is no package
    try:
        with contextlib.redirect_stdout(stdout), pytest.raises(SystemExit) as done, \
                warnings.catch_warnings():
            # another test may have imported the module: runpy warns, and runs it all the same
            warnings.filterwarnings("ignore", "'.*' found in sys.modules", RuntimeWarning)
            runpy.run_module(module, run_name="__main__", alter_sys=True)
    finally:
        sys.argv, sys.path = argv, path
    assert done.value.code in (0, None)
    return set(re.findall(r"(?<![\w-])(--?[a-zA-Z][\w-]*)", stdout.getvalue()))


@pytest.mark.parametrize(("where", "words"), MODULES, ids=[w for w, _ in MODULES])
def test_every_python_module_and_option_exists(where: str, words: list[str]) -> None:
    module = words[2]
    if "<" in module:
        return  # a placeholder: flows.<name>
    path = REPO / module.replace(".", "/")
    assert path.with_suffix(".py").is_file() or (path / "__main__.py").is_file(), \
        f"{where}: no module {module}"
    options = [w for w in words[3:] if OPTION.match(w)]
    if options:
        unknown = set(options) - module_options(module)
        assert not unknown, f"{where}: `python -m {module}` has no option {sorted(unknown)}"


def test_the_exit_code_table_is_the_exit_codes() -> None:
    text = (REPO / "docs" / "cli.md").read_text(encoding="utf-8")
    table = text[text.index("| exit code | meaning |"):].split("\n\n", 1)[0]
    rows = dict(re.findall(r"^\| (\d+) \| (.*) \|$", table, re.M))
    assert {int(c) for c in rows} - {SIGINT} == {c.value for c in ExitCode} - {SIGINT}
    assert "Ctrl-C" in rows.get(str(SIGINT), "Ctrl-C")  # the shell's code for an interrupt
    assert all(f"{c.value} " in EXIT_CODES_HELP for c in ExitCode)  # what `evoeye --help` says


EXIT = re.compile(r"exits?(?: with)?(?: code)?(?: is)? (\d+)|exit code (?:is )?(\d+)")


def test_every_stated_exit_code_is_one_the_command_uses() -> None:
    strict = int(ExitCode.CHECK_FAILED)
    for page in PAGES:
        for line in page.read_text(encoding="utf-8").splitlines():
            for match in EXIT.finditer(line):
                code = int(match.group(1) or match.group(2))
                assert code in {c.value for c in ExitCode} | {SIGINT}, f"{page.name}: {line}"
                if "--strict" in line[:match.start()]:
                    assert code == strict, f"{page.name}: --strict exits {strict}: {line}"


LINK = re.compile(r"\]\(([^)\s]+)\)")


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower().replace("`", ""))
    return text.replace(" ", "-")


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(REPO)) for p in PAGES])
def test_every_relative_link_leads_somewhere(page: Path) -> None:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    for target in LINK.findall(text):
        if re.match(r"^[a-z]+:", target):
            continue  # http:, https:, mailto:
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        assert file.exists(), f"{page.name}: {target} leads nowhere"
        if anchor and file.suffix == ".md":
            headings = re.findall(r"^#+ (.+)$", file.read_text(encoding="utf-8"), re.M)
            assert anchor in {_anchor(h) for h in headings}, f"{page.name}: no #{anchor}"
