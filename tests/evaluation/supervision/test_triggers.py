"""Trigger names: two FusionMonitor versions side by side in one supervision."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from evoeye.evaluation.supervision.triggers import TriggerSpec, trigger_names


def monitor(name: str, version: str) -> SimpleNamespace:
    return SimpleNamespace(name=name, version=version)


def spec(name: str, source: str, version: str) -> TriggerSpec:
    return TriggerSpec(name, source, version, version, (0.5,), ("FPR 0.01",), (0.01,), (0.5,))


def test_a_second_version_of_a_name_is_named_by_its_version() -> None:
    names = trigger_names([monitor("fusion", "fusion-aaa"), monitor("ttc", "ttc"),
                           monitor("fusion", "fusion-bbb")])
    assert names == ["fusion", "ttc", "fusion-bbb"]
    with pytest.raises(ValueError, match="fusion-aaa is given twice"):
        trigger_names([monitor("fusion", "fusion-aaa")] * 3)


def test_reports_label_each_fusion_monitor_apart() -> None:
    assert spec("fusion", "version", "fusion-aaa").label == "FusionMonitor"
    assert spec("fusion-bbb", "version", "fusion-bbb").label == "FusionMonitor fusion-bbb"
    assert spec("ttc", "baseline", "ttc").label == "ttc"
