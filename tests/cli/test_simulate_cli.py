"""`evoeye simulate`: exit codes, plain batch names, and a root that cannot be written."""

from __future__ import annotations

import stat
from pathlib import Path

import pytest
from typer.testing import CliRunner

import evoeye.batch
from evoeye.batch import plan_uniform
from evoeye.cli import app
from evoeye.cli.errors import ExitCode
from evoeye.paths import BadNameError, DataRoot

runner = CliRunner()
SIM = ["simulate", "--scenario", "highway-cut-in", "--n", "2"]


@pytest.mark.parametrize("lockstep", ["1", "64"])
def test_failed_runs_give_exit_code_3_and_say_how_many(tmp_path, monkeypatch, lockstep) -> None:
    def broken(*args, **kwargs):
        raise OSError("disk on fire")

    monkeypatch.setattr(evoeye.batch, "run_episode", broken)  # one run at a time
    monkeypatch.setattr(evoeye.batch, "run_indexed", broken)  # runs stepped together
    result = runner.invoke(app, [*SIM, "--root", str(tmp_path), "--lockstep", lockstep])
    assert result.exit_code == ExitCode.PARTIAL, result.output
    assert "2 of 2 runs failed" in result.output and "disk on fire" in result.output


@pytest.mark.parametrize("kind", ["file", "read-only"])
def test_a_root_that_cannot_be_written_is_one_line_and_exit_2(tmp_path, kind,
                                                              monkeypatch) -> None:
    root = tmp_path / "root"
    if kind == "file":
        root.write_text("not a folder")
    else:
        root.mkdir()
        root.chmod(stat.S_IRUSR | stat.S_IXUSR)
        real_mkdir = Path.mkdir

        def read_only(self, *args, **kwargs):  # as root, permissions would not apply: the
            if root in (self, *self.parents):  # file system's answer is what is tested
                raise PermissionError(13, "Permission denied", str(self))
            return real_mkdir(self, *args, **kwargs)

        monkeypatch.setattr(Path, "mkdir", read_only)
    result = runner.invoke(app, [*SIM, "--root", str(root)])
    assert result.exit_code == ExitCode.USER_ERROR, result.output
    assert "Traceback" not in result.output and "hint: check --root" in result.output
    assert len(result.output.strip().splitlines()) == 2  # the error and its hint


@pytest.mark.parametrize("batch", ["../../../x", "/abs/path", "x/y", "..", ".hidden", "a..b"])
def test_batch_must_be_a_plain_name_before_anything_runs(tmp_path, batch) -> None:
    root = tmp_path / "root"
    result = runner.invoke(app, [*SIM, "--root", str(root), "--batch", batch])
    assert result.exit_code == ExitCode.USER_ERROR and "plain name" in result.output
    assert not root.exists() and not list(tmp_path.rglob("*.mcap*"))
    with pytest.raises(BadNameError):
        plan_uniform("highway-cut-in", 2, 0, batch=batch)
    with pytest.raises(BadNameError):
        DataRoot.resolve(root).run_log("highway-cut-in", batch, "x")


def test_debug_shows_the_traceback(tmp_path) -> None:
    (tmp_path / "root").write_text("not a folder")
    result = runner.invoke(app, ["--debug", *SIM, "--root", str(tmp_path / "root")])
    assert result.exit_code != 0 and isinstance(result.exception, OSError)


def test_the_summary_keeps_the_scenario_name_whole_in_a_pipe(tmp_path) -> None:
    result = CliRunner(env={"COLUMNS": "40"}).invoke(app, [*SIM, "--root", str(tmp_path)])
    assert result.exit_code == ExitCode.OK, result.output
    row = next(line for line in result.stdout.splitlines() if "highway-cut" in line)
    assert "highway-cut-in" in row and "…" not in result.stdout


def test_ads_names_a_profile_and_its_runs_go_to_a_batch_of_their_own(tmp_path) -> None:
    result = runner.invoke(app, [*SIM[:-1], "1", "--ads", "firm-yield", "--root", str(tmp_path)])
    assert result.exit_code == ExitCode.OK, result.output
    logs = list((tmp_path / "runs" / "highway-cut-in").glob("*/*.mcap"))
    assert [p.parent.name for p in logs] == ["uniform-firm-yield-seed0"]
    refused = runner.invoke(app, [*SIM, "--ads", "reckless", "--root", str(tmp_path / "x")])
    assert refused.exit_code == 2
    assert "known: default, cautious, firm-yield, defensive" in refused.output
    assert not (tmp_path / "x").exists()  # refused before anything ran


def test_world_names_a_variant_and_its_runs_go_to_a_batch_of_their_own(tmp_path) -> None:
    from evoeye.log import read_run

    result = runner.invoke(app, [*SIM[:-1], "1", "--world", "follower", "--root", str(tmp_path)])
    assert result.exit_code == ExitCode.OK, result.output
    (log,) = (tmp_path / "runs" / "highway-cut-in").glob("*/*.mcap")
    assert log.parent.name == "uniform-follower-seed0"
    assert read_run(log, topics=()).metadata["world"] == "follower"
    refused = runner.invoke(app, [*SIM, "--world", "fog", "--root", str(tmp_path / "x")])
    assert refused.exit_code == 2 and "known: default, follower" in refused.output
    other = runner.invoke(app, ["simulate", "--scenario", "unprotected-intersection", "--n", "1",
                                "--world", "follower", "--root", str(tmp_path / "y")])
    assert other.exit_code == 2 and "no variant of unprotected-intersection" in other.output
