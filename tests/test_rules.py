"""House rules checked on the source, beside the import contracts `make test` runs first
(`lint-imports`, configured in pyproject.toml: the layers, a pure search, Prefect in flows/)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PROJECT = Path(__file__).resolve().parents[1]
SOURCES = sorted(p for package in ("evoeye", "flows") for p in (PROJECT / package).rglob("*.py"))


def module_of(path: Path) -> str:
    parts = path.relative_to(PROJECT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def private_imports(source: str, here: str) -> list[str]:
    """The private names (`_x`, not `__x__`) `source`, the module `here`, imports from another
    evoeye or flows module."""
    return [f"{node.module}.{alias.name}" for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.ImportFrom) and node.module
            and node.module.split(".")[0] in ("evoeye", "flows") and node.module != here
            for alias in node.names
            if alias.name.startswith("_") and not alias.name.endswith("__")]


def test_private_imports_are_found_inside_functions_too() -> None:
    source = ("from evoeye import __version__\nfrom evoeye.a import b, _c\n"
              "def f():\n    from flows.x import _y\n    from evoeye.here import _mine\n")
    assert private_imports(source, "evoeye.here") == ["evoeye.a._c", "flows.x._y"]


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PROJECT)))
def test_no_module_imports_another_modules_private_names(path: Path) -> None:
    found = private_imports(path.read_text(encoding="utf-8"), module_of(path))
    assert not found, f"{module_of(path)} imports private names: {found}"
