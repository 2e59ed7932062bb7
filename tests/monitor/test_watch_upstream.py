"""`evoeye watch` on a recording evoeye did not write (tests/data/autoware/upstream_bag.py): it
scores every frame and alarms before the collision; a file it cannot read is one line.

The monitor is the tiny one (tests/monitor/conftest.py): it learnt that an obstacle a few metres
ahead with the brake fully on is unsafe, and obstacles 30 m away safe — what the drive shows
when it brakes late towards the stopped car, and before.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import orjson
import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.errors import ExitCode

HERE = Path(__file__).resolve().parents[1] / "data" / "autoware" / "upstream_bag.py"
_spec = importlib.util.spec_from_file_location("upstream_bag", HERE)
up = sys.modules.setdefault("upstream_bag", importlib.util.module_from_spec(_spec))
_spec.loader.exec_module(up)


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> tuple[up.Drive, Path]:
    drive, store = up.Drive(seed=2), up.upstream_store()
    bag = up.write_mcap(tmp_path_factory.mktemp("upstream") / "drive", drive.messages(store),
                        store)
    return drive, next(bag.glob("*.mcap"))


def test_watch_scores_an_upstream_recording_and_alarms_before_the_collision(
        tiny, trained, recording, tmp_path) -> None:
    drive, mcap = recording
    result = CliRunner().invoke(app, ["watch", str(mcap), "--monitor", trained, "--root",
                                      str(tiny.root.path), "--out", str(tmp_path / "risk.mcap"),
                                      "--idle-s", "0", "--fpr", "0.01"])
    assert result.exit_code == 0, result.output
    rows = [orjson.loads(line) for line in result.stdout.splitlines() if line.startswith("{")]
    assert len(rows) == 98  # every 20 Hz frame, 0.103 … 4.953 s after the first stamp
    # frame times count from the whole second before the first frame
    offset_s = (up.T0_NS % 1_000_000_000) / 1e9
    contact_s, brake_s = offset_s + drive.contact_s, offset_s + drive.brake_at_s
    alarms = [r["t_s"] for r in rows if r["alarm"]]
    assert alarms and brake_s <= alarms[0] < contact_s - 0.5  # warned over 0.5 s ahead …
    assert all(r["alarm"] for r in rows if r["t_s"] >= alarms[0])  # … and from then on


def test_watch_on_a_file_it_cannot_read_is_one_line(tiny, trained, tmp_path) -> None:
    bad = tmp_path / ("a-recording-with-a-long-name-" * 3 + ".mcap")
    bad.write_bytes(b"not an mcap file at all")
    result = CliRunner().invoke(app, ["watch", str(bad), "--monitor", trained, "--root",
                                      str(tiny.root.path), "--idle-s", "0"])
    assert result.exit_code == ExitCode.USER_ERROR, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert errors == [f"error: {bad}: (bag): not an MCAP file (bad leading magic)"]
