"""Recorded supervision settings stay readable: the fallback they used, whatever the default is
now."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from evoeye.evaluation.supervision.settings import Settings, recorded_fallback
from evoeye.sim.supervisor import FALLBACKS, FallbackConfig

RESULTS = Path(__file__).parents[3] / "docs" / "results"


@pytest.mark.parametrize("scenario", ["highway-cut-in", "unprotected-intersection"])
def test_a_recorded_supervision_reads_back_with_the_fallback_it_used(scenario: str) -> None:
    recorded = json.loads((RESULTS / f"supervision-comfort-{scenario}.json").read_text())[
        "settings"]
    settings = Settings.of(recorded)
    assert settings.fallback == FALLBACKS["comfort"] != FallbackConfig()
    assert settings.to_dict()["fallback"] == recorded["fallback"]  # its part of the key


def test_a_value_a_record_lacks_is_the_comfort_fallbacks_the_only_one_before_names() -> None:
    assert recorded_fallback({"decel_mps2": 7.0}) == FallbackConfig(7.0, jerk_mps3=10.0)
    staged = {**FALLBACKS["production"].to_dict(), "stage_decel_mps2": 4.0, "stage_s": 0.3}
    assert recorded_fallback(staged).stage_s == 0.3
    assert recorded_fallback(FallbackConfig().to_dict()) == FALLBACKS["production"]
