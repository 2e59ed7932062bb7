"""`evoeye evaluate`: the Markdown table and `--json` carry the same figures."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

import evoeye.cli.evaluate  # noqa: F401  (registers the command)
from evoeye.cli import app
from evoeye.evaluation.report import pct, rate

RUNNER = CliRunner()


def _args(root, splits, *extra: str) -> list[str]:
    return ["evaluate", "--root", str(root.path), "--scenario", "highway-cut-in",
            "--baselines", "ttc,rss", "--no-latency", "--split-seed", str(splits.seed),
            "--train-frac", str(splits.train_frac), "--val-frac", str(splits.val_frac), *extra]


LABELS = {"TTC": "ttc", "RSS": "rss"}
SECTIONS = {"per frame": "frame", "per run, a warning = 1 alarm frame": "1",
            "per run, a warning = 3 consecutive alarm frames": "3"}


def _markdown_rows(text: str) -> dict[tuple[str, str], list[str]]:
    """(section, monitor) → cells of the table rows in `text`; the headline's section is
    "headline", the RQ1 tables' "frame", "1" and "3"."""
    rows, section = {}, None
    for line in text.splitlines():
        if line.startswith("## highway-cut-in"):
            section = "headline"
        elif line.startswith("### highway-cut-in: "):
            section = SECTIONS[line.split(": ", 1)[1]]
        elif line.startswith("#"):
            section = None
        elif line.startswith("| ") and section is not None:
            cells = [c.strip() for c in line.strip("|").split("|")]
            if cells[0] in LABELS:
                rows[(section, LABELS[cells[0]])] = cells[1:]
    return rows


def _expected(monitor: dict, section: str) -> list[str]:
    block = monitor["frame"] if section == "frame" else monitor["scenario"][section]
    cells = []
    for f in ("0.05", "0.01"):
        cells += [rate(block["at_fpr"][f], k) for k in ("precision", "recall", "f1")]
    return cells + [pct(block["auroc"]), pct(block["auprc"])]


def test_json_and_markdown_carry_the_same_numbers(eval_root, splits) -> None:
    as_json = RUNNER.invoke(app, _args(eval_root, splits, "--json", "--name", "cli-json"))
    assert as_json.exit_code == 0, as_json.output
    data = json.loads(as_json.stdout)
    (report,) = data["reports"]
    assert report["logical_scenario"] == "highway-cut-in"
    as_md = RUNNER.invoke(app, _args(eval_root, splits, "--name", "cli-md"))
    assert as_md.exit_code == 0, as_md.output
    assert "report: " in as_md.stdout and "cli-md/report.html" in as_md.stdout
    assert "evaluate: 100%" in as_md.stderr and "2/2 [" in as_md.stderr  # the progress bar
    assert "step/s]" in as_md.stderr or "s/step]" in as_md.stderr
    assert as_md.stdout.index("## highway-cut-in") < as_md.stdout.index("## Details")
    rows = _markdown_rows(as_md.stdout)
    assert set(rows) == {(s, m) for s in ("headline", *SECTIONS.values()) for m in LABELS.values()}
    for monitor in report["monitors"]:
        for section in SECTIONS.values():
            assert rows[(section, monitor["name"])] == _expected(monitor, section)
        lead = monitor["scenario"]["3"]["lead_time"]["0.05"]  # the headline: K = 3, FPR 0.05
        warned = rows[("headline", monitor["name"])][0]
        reached = monitor["scenario"]["3"]["at_fpr"]["0.05"]["reachable"]
        assert warned == (f"{lead['detected']} of {lead['violations']}" if reached else "n/r")


@pytest.mark.parametrize(("extra", "message"), [
    (["--baselines", "none"], "nothing to evaluate"),
    (["--baselines", "ttc,foo"], "unknown baseline"),
])
def test_bad_arguments_are_refused(eval_root, splits, extra, message) -> None:
    args = [a for a in _args(eval_root, splits) if a not in ("--baselines", "ttc,rss")]
    result = RUNNER.invoke(app, args + extra)
    assert result.exit_code != 0 and message in result.output
