"""`evoeye supervise`: `--json` rows hold exactly the listed fields, the report and the docs
files are written; a killed supervision resumes to the same records."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

import evoeye.cli.supervise  # noqa: F401  (registers the command)
from evoeye.cli import app
from evoeye.evaluation.supervision.summary import ROW_FIELDS

RUNNER = CliRunner()


def _args(sup, *extra: str, batch: str | None = None) -> list[str]:
    s = sup.splits
    return ["supervise", "--root", str(sup.root.path), "--scenario", sup.scenario,
            "--batch", batch or sup.batch, "--baselines", "ttc-2d", "--monitor", "none",
            "--fprs", ",".join(str(f) for f in sup.fprs), "--split-seed", str(s.seed),
            "--train-frac", str(s.train_frac), "--val-frac", str(s.val_frac), *extra]


def test_json_rows_hold_exactly_the_listed_fields(sup, tmp_path) -> None:
    docs = tmp_path / "docs"
    res = RUNNER.invoke(app, _args(sup, "--json", "--name", "cli", "--docs", str(docs),
                                   "--workers", "2"))  # spawned workers load the triggers
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["rows"] and all(tuple(r) == ROW_FIELDS for r in out["rows"])
    assert {r["trigger"] for r in out["rows"]} == {"ttc-2d"}
    assert {r["runs"] for r in out["rows"]} == {4}
    assert {r["collisions_unsupervised"] for r in out["rows"]} == {2}
    assert all(r["collisions_prevented"] <= 2 for r in out["rows"])
    report = sup.root.reports / "cli"
    assert (report / "supervision.md").read_text().startswith("# Monitor in the loop")
    assert "<svg" in (report / "report.html").read_text()
    md = (docs / f"supervision-{sup.scenario}.md").read_text()
    assert f"(supervision-{sup.scenario}.svg)" in md and "ttc-2d: operating curve" in md
    assert (docs / f"supervision-{sup.scenario}.svg").read_text().startswith(
        '<svg xmlns="http://www.w3.org/2000/svg"')
    assert json.loads((docs / f"supervision-{sup.scenario}.json").read_text())["rows"] == \
        out["rows"]


def test_bad_options_are_one_line_errors(sup) -> None:
    res = RUNNER.invoke(app, _args(sup, "--fprs", "0.05,x"))
    assert res.exit_code == 2 and "--fprs" in res.output
    res = RUNNER.invoke(app, _args(sup, "--test-batch", "sup", batch="nothing-here"))
    assert res.exit_code == 2 and "no run logs" in res.output


@pytest.mark.slow  # two interpreters start highway-env and re-simulate four runs: ≈ 30 s
@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="needs /proc")
def test_a_killed_supervision_resumes_to_the_same_records(sup) -> None:
    cmd = [sys.executable, "-m", "evoeye", *_args(sup, "--baselines", "ttc,ttc-2d",
                                                   "--name", "killed")]
    pattern = f"{sup.scenario}/{sup.batch}/*/runs"
    before = set(sup.root.supervision.glob(pattern))  # other tests' supervisions
    first = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    runs = None
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and first.poll() is None:
            ours = set(sup.root.supervision.glob(pattern)) - before
            if ours and 0 < len(list(next(iter(ours)).glob("*.json"))) < 4:
                first.send_signal(signal.SIGKILL)
                runs = ours.pop()
                break
            time.sleep(0.05)
    finally:
        first.kill()
        first.wait(10)
    if runs is None:
        pytest.skip("the supervision finished before it could be killed")
    done = {p.name: p.read_bytes() for p in runs.glob("*.json")}
    rerun = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    after = {p.name: p.read_bytes() for p in runs.glob("*.json")}
    assert len(after) == 4 and all(after[n] == b for n, b in done.items())
    assert not list(runs.glob("*.tmp"))
