"""What a newcomer tripped on: unknown names are refused naming the known ones, hints say
what is true, an empty root is warned of, and options with a fixed set of values list it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.defaults import METHOD_NAMES, STRATEGY_NAMES
from evoeye.scenarios import SCENARIOS

KNOWN = ", ".join(SCENARIOS)


def run(*args: str) -> tuple[int, str]:
    done = CliRunner(env={"COLUMNS": "400"}).invoke(app, list(args))
    return done.exit_code, done.output


@pytest.mark.parametrize(("args", "said"), [
    (("simulate", "--scenario", "external", "--n", "2"),
     f"logical scenario 'external' is recorded, not simulated; simulated ones: {KNOWN}"),
    (("train", "--scenario", "pedestrian-crossing"),
     f"unknown logical scenario 'pedestrian-crossing'; simulated ones: {KNOWN}"),
    (("demo", "--scenario", f"{next(iter(SCENARIOS))},roundabout"),
     f"unknown logical scenario 'roundabout'; simulated ones: {KNOWN}"),
    (("audit", "--scenario", "roundabout"),
     f"unknown logical scenario 'roundabout'; known: {KNOWN}, external"),
])
def test_an_unknown_scenario_is_refused_naming_the_known_ones(tmp_path: Path, args, said):
    code, output = run(*args, "--root", str(tmp_path / "r"))
    assert code == 2 and said in " ".join(output.split())
    assert not (tmp_path / "r").exists()  # refused before anything was written


def test_ingest_and_sql_on_an_empty_root_warn_and_create_nothing(tmp_path: Path) -> None:
    root = tmp_path / "r"
    root.mkdir()
    code, output = run("ingest", "--root", str(root))
    assert code == 0 and "warning: no run logs under" in output and "nothing to ingest" in output
    assert list(root.iterdir()) == []  # no warehouse for nothing
    code, output = run("sql", "SELECT * FROM scenarios", "--root", str(root))
    assert code == 0 and "holds no run yet: `evoeye simulate`, then `evoeye ingest`" in " ".join(
        output.split())


def test_a_failed_training_says_what_the_warehouse_holds(tmp_path: Path) -> None:
    from evoeye.cli.monitor import ingested_words
    from evoeye.paths import DataRoot

    crossing, highway = "unprotected-intersection", "highway-cut-in"
    root = str(tmp_path / "r")
    assert run("simulate", "--scenario", crossing, "--n", "2", "--root", root)[0] == 0
    assert run("ingest", "--root", root)[0] == 0
    data = DataRoot.existing(root)
    assert ingested_words(data, highway).startswith(f"no run of {highway} is ingested: ")
    assert ingested_words(data, crossing).startswith(f"the warehouse holds 2 runs of {crossing}")
    code, output = run("train", "--scenario", highway, "--root", root)
    assert code != 0 and f"no run of {highway} is ingested" in " ".join(output.split())
    assert "check --scenario" not in output


@pytest.mark.parametrize(("command", "names"), [
    ("simulate", tuple(SCENARIOS)),
    ("demo", tuple(SCENARIOS)),
    ("evolve", STRATEGY_NAMES + ("replay", "finetune", "retrain", "warm", "raw",
                                  "prior-corrected")),
    ("experiment", METHOD_NAMES),
])
def test_options_with_a_fixed_set_of_values_list_it_in_help(command: str, names) -> None:
    code, output = run(command, "--help")
    flat = "".join(output.split())  # help wraps lines, even inside a name
    listed = set(re.findall(r"(?<=[:,])([\w-]+)(?=[,.])", flat))
    assert code == 0 and set(names) <= listed, set(names) - listed
