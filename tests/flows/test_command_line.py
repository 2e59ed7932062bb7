"""`python -m flows.<name>`: --help for every flow, validation first, the result as JSON."""

from __future__ import annotations

import json
import os
import runpy
import sys

import pytest

# Import the flows (and so Prefect, whose log handlers bind to the streams of the moment) before
# any test captures stdout/stderr.
import flows.evaluate  # noqa: F401
import flows.evolve  # noqa: F401
import flows.experiment  # noqa: F401
import flows.ingest  # noqa: F401
import flows.simulate  # noqa: F401
import flows.train  # noqa: F401

pytestmark = pytest.mark.filterwarnings("ignore:.*found in sys.modules:RuntimeWarning")
FLOWS = ("simulate", "ingest", "train", "evaluate", "evolve", "experiment")


def _run_module(name: str, args: list[str], monkeypatch) -> int:
    monkeypatch.setattr(sys, "argv", [f"/x/flows/{name}.py", *args])
    with pytest.raises(SystemExit) as done:
        runpy.run_module(f"flows.{name}", run_name="__main__")
    return done.value.code


@pytest.mark.parametrize("name", FLOWS)
def test_every_flow_has_a_help(name: str, monkeypatch, capsys) -> None:
    assert _run_module(name, ["--help"], monkeypatch) == 0
    text = capsys.readouterr().out
    assert f"python -m flows.{name}" in text and "--root" in text
    assert "PREFECT_API_URL" in text  # how to skip the temporary server


def test_bad_parameters_are_refused_before_anything_runs(monkeypatch, capsys, tmp_path) -> None:
    args = ["--scenario", "roundabout", "--root", str(tmp_path / "r")]
    assert _run_module("simulate", args, monkeypatch) == 2
    assert "unknown logical scenario" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_a_flow_runs_from_the_command_line(prefect_server, tmp_path, capsys) -> None:
    from flows.command_line import run_from_command_line
    from flows.ingest import IngestParams, ingest_flow

    (tmp_path / "data").mkdir()
    result = run_from_command_line(IngestParams, ingest_flow, None,
                                   ["--root", str(tmp_path / "data"), "--runs-per-part", "4"])
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads(json.dumps(result)) and printed["ingested"] == []
    assert (tmp_path / "data" / "warehouse").is_dir()


def test_the_temporary_server_gets_a_generous_start_up_timeout(monkeypatch) -> None:
    import importlib

    from prefect.settings import PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS as TIMEOUT

    import flows

    # flows/__init__.py ran before Prefect was imported, so Prefect's settings have it
    assert TIMEOUT.value() >= 120  # Prefect's own default, 20 s, fails on a busy machine
    monkeypatch.setenv("PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS", "45")
    importlib.reload(flows)  # a user's own setting wins
    assert os.environ["PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS"] == "45"


def test_the_flows_refuse_a_batch_that_is_not_a_plain_name() -> None:
    from flows.simulate import SimulateParams

    with pytest.raises(ValueError, match="plain name"):
        SimulateParams(batch="../../../x")
    assert SimulateParams(batch="nightly-2.b_1").batch == "nightly-2.b_1"


def test_demo_with_too_small_an_n_is_one_line(monkeypatch, capsys) -> None:
    monkeypatch.setattr(sys, "argv", ["/x/flows/demo.py", "--n", "3"])
    from flows.demo import main

    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 2 and "greater than or equal to 8" in err
    usage, error = err.strip().split("\npython -m flows.demo: error: ")  # the usage may wrap
    assert usage.startswith("usage:") and "Traceback" not in err
    assert "greater than or equal to 8" in error and "\n" not in error
