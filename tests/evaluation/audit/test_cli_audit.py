"""`evoeye audit` end to end on a tiny simulated batch: simulate, audit, ingest, audit again."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.errors import ExitCode
from evoeye.paths import DataRoot
from evoeye.store import Warehouse

RUNNER = CliRunner()
S1 = "highway-cut-in"


def _files(root: Path) -> dict[str, int]:
    """Every file outside reports/ with its modification time (ns)."""
    return {str(p): p.stat().st_mtime_ns for p in root.rglob("*")
            if p.is_file() and "reports" not in p.parts}


@pytest.fixture(scope="module")
def batch_root(tmp_path_factory: pytest.TempPathFactory) -> DataRoot:
    root = DataRoot.resolve(tmp_path_factory.mktemp("audit") / "data")
    done = RUNNER.invoke(app, ["simulate", "--scenario", S1, "--n", "6", "--seed", "3",
                               "--root", str(root.path)])
    assert done.exit_code == 0, done.output
    return root


def _audit(root: DataRoot, *extra: str) -> tuple[int, dict]:
    out = RUNNER.invoke(app, ["audit", "--root", str(root.path), "--scenario", S1, "--json",
                              "--workers", "2", *extra])
    return out.exit_code, json.loads(out.stdout)


def test_audit_before_and_after_ingest(batch_root: DataRoot) -> None:
    before = _files(batch_root.path)
    code, report = _audit(batch_root)
    assert code == 0
    (s,) = report["logical_scenarios"]
    assert s["runs"] == 6 and s["clock_auroc"] is None and s["attribution"] is None
    assert all(r["kinematics"] is not None for r in s["per_run"])
    judged = {v["criterion"]: v for v in s["verdicts"]}
    assert judged["clock-only AUROC"]["passed"] is None
    assert "evoeye ingest" in judged["clock-only AUROC"]["value"]
    assert s["context_auroc"] is None and judged["context-only AUROC"]["passed"] is None
    assert _files(batch_root.path) == before  # read-only

    assert RUNNER.invoke(app, ["ingest", "--root", str(batch_root.path)]).exit_code == 0
    code, report = _audit(batch_root)
    (s,) = report["logical_scenarios"]
    wh = Warehouse(batch_root)
    collided = wh.sql("SELECT count(*) FILTER (WHERE collided) FROM scenarios").to_pylist()
    assert s["collided_runs"] == next(iter(collided[0].values()))
    eligible = wh.sql("SELECT count(*) AS n FROM frame_labels "
                      "WHERE collision_time_s IS NULL OR t_s < collision_time_s").to_pylist()
    clock = s["clock_auroc"]
    assert clock["frames"] == eligible[0]["n"] and clock["runs"] == 6
    context = s["context_auroc"]  # the same pre-collision frames, RQ1's control out of fold
    assert (context["frames"], context["unsafe_frames"]) == (clock["frames"],
                                                             clock["unsafe_frames"])
    verdict = {v["criterion"]: v for v in s["verdicts"]}["context-only AUROC"]
    auroc = context["auroc"]
    assert verdict["passed"] == (None if auroc is None else auroc <= 0.95)
    written = json.loads((batch_root.reports / f"audit-{S1}-all" / "audit.json").read_text())
    assert written == report
    md = (batch_root.reports / f"audit-{S1}-all" / "audit.md").read_text()
    assert "clock-only AUROC" in md and "not explained yet" in md
    assert "Context-only control (RQ1's" in md


def test_strict_fails_exactly_when_a_criterion_fails(batch_root: DataRoot) -> None:
    code, report = _audit(batch_root, "--strict")
    failed = any(v["passed"] is False for s in report["logical_scenarios"] for v in s["verdicts"])
    assert report["failed"] is failed
    assert code == (4 if failed else 0)  # ExitCode.CHECK_FAILED


def test_an_unreadable_log_is_reported_not_fatal(batch_root: DataRoot, tmp_path: Path) -> None:
    root = DataRoot.resolve(tmp_path / "copy")
    src = sorted(batch_root.runs.rglob("*.mcap"))[0]
    dst = root.runs / S1 / "b" / src.name
    dst.parent.mkdir(parents=True)
    dst.write_bytes(src.read_bytes()[:5000])  # truncated
    code, report = _audit(root)
    (s,) = report["logical_scenarios"]
    assert code == 0 and s["unreadable_runs"] == 1
    assert "truncated" in s["per_run"][0]["error"]


def test_a_batch_the_root_does_not_hold_is_refused_naming_those_it_does(
        batch_root: DataRoot) -> None:
    asked = RUNNER.invoke(app, ["audit", "--root", str(batch_root.path), "--batch", "demo"])
    assert asked.exit_code == ExitCode.USER_ERROR
    assert "no run logs of batch 'demo'" in asked.output
    assert f"{S1}/uniform-seed3 (6 logs)" in asked.output  # what the root holds
    assert not (batch_root.reports / "audit-all-demo").exists()  # no empty report
    code, report = _audit(batch_root, "--batch", "uniform-seed3")  # the batch it does hold
    assert code == 0 and [s["runs"] for s in report["logical_scenarios"]] == [6]
    outside = RUNNER.invoke(app, ["audit", "--root", str(batch_root.path), "--batch", "../x"])
    assert outside.exit_code == ExitCode.USER_ERROR and "not a plain name" in outside.output


def test_an_empty_root_is_refused(tmp_path: Path) -> None:
    root = DataRoot.resolve(tmp_path / "empty")
    root.runs.mkdir(parents=True)
    out = RUNNER.invoke(app, ["audit", "--root", str(root.path)])
    assert out.exit_code == ExitCode.USER_ERROR and "it holds none" in out.output
