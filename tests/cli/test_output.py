"""The CLI's progress bar for step-reporting libraries (evaluate, experiment)."""

from __future__ import annotations

import pytest

from evoeye.cli.output import StepBar


def test_a_step_ends_when_the_next_begins_and_the_last_on_success(capsys) -> None:
    with StepBar("experiment") as bar:
        for msg in ("campaign a", "  round 1", "  round 2"):
            bar(msg)
            assert bar.bar.n == ("campaign a", "  round 1", "  round 2").index(msg)
    assert bar.bar.n == 3
    err = capsys.readouterr().err
    assert "campaign a" in err and "  round 2" in err and "3step [" in err


def test_a_failed_step_is_not_counted() -> None:
    with pytest.raises(RuntimeError), StepBar("evaluate", total=2) as bar:
        bar("training")
        raise RuntimeError("boom")
    assert bar.bar.n == 0
