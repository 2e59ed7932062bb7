"""`evoeye train` from the shell: prints the version, the validation metrics and the card."""

from __future__ import annotations

from typer.testing import CliRunner

import evoeye.cli.monitor  # noqa: F401  (registers the commands)
from evoeye.cli.app import app
from evoeye.cli.errors import ExitCode
from evoeye.monitor.registry import read_card
from evoeye.scenarios import SCENARIOS


def test_train_command_prints_version_metrics_and_card(tiny) -> None:
    result = CliRunner().invoke(app, [
        "train", "--root", str(tiny.root.path), "--scenario", tiny.scenario,
        "--horizon-s", str(tiny.horizon_s), "--context-len", "3", "--epochs", "2",
        "--modules", "perception+prediction", "--seed", "4",
    ], env={"COLUMNS": "160"})
    assert result.exit_code == 0, result.output
    version = result.output.split("version: ")[-1].strip()
    card = read_card(tiny.root, version)
    assert card["context_len"] == 3 and card["modules"] == ["perception", "prediction"]
    assert card["hyperparameters"]["seed"] == 4 and card["training"]["epochs_run"] == 2
    # by default the command trains the monitor a supervisor's trigger needs (its kinematics
    # and critical target; the caller's --context-len won over the recipe's)
    hyper = card["hyperparameters"]
    assert (hyper["recipe"], hyper["target"], card["config"]["kinematics"]) == (
        "lookahead-v1", "critical", True)
    assert "epoch   2" in result.output and "AUROC" in result.output
    assert f"monitors/{version}/card.json" in result.output.replace("\n", "")


def test_train_command_reports_bad_input_without_a_traceback(tiny) -> None:
    result = CliRunner().invoke(app, ["train", "--root", str(tiny.root.path), "--scenario",
                                      "nowhere"])
    assert result.exit_code == 2 and "unknown logical scenario 'nowhere'" in result.output
    other = next(s for s in SCENARIOS if s != tiny.scenario)  # known, with no run here
    result = CliRunner().invoke(app, ["train", "--root", str(tiny.root.path), "--scenario",
                                      other], env={"COLUMNS": "200"})
    assert result.exit_code == ExitCode.USER_ERROR
    assert "training and validation windows" in result.output
    assert f"no run of {other} is ingested" in " ".join(result.output.split())
    result = CliRunner().invoke(app, ["train", "--root", str(tiny.root.path), "--scenario",
                                      tiny.scenario, "--init-from", "fusion-000000000000"])
    assert result.exit_code == ExitCode.USER_ERROR and "no monitor version" in result.output
    result = CliRunner().invoke(app, ["train", "--root", str(tiny.root.path), "--scenario",
                                      tiny.scenario, "--keep-parent"])
    assert result.exit_code == ExitCode.USER_ERROR and "--init-from" in result.output
    assert "Traceback" not in result.output
    missing = CliRunner().invoke(app, ["train", "--root", str(tiny.root.path / "nowhere"),
                                       "--scenario", tiny.scenario])
    assert missing.exit_code == ExitCode.USER_ERROR and "no data root at" in missing.output


def test_a_fine_tune_that_loses_says_it_kept_the_parent(tiny, trained: str) -> None:
    result = CliRunner().invoke(app, [
        "train", "--root", str(tiny.root.path), "--scenario", tiny.scenario,
        "--horizon-s", str(tiny.horizon_s), "--init-from", trained, "--epochs", "1",
        "--lr", "5.0", "--keep-parent",  # the learning rate wrecks whatever it touches
    ], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert f"no epoch of the fine-tune beat {trained} on the validation split" in result.output
    assert result.output.split("version: ")[-1].strip() == trained
