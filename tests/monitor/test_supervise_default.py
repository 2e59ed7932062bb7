"""`evoeye supervise` without --monitor runs the product's monitor: the newest FusionMonitor
trained on the scenario (a campaign's G_0), and says which; baselines alone without one."""

from __future__ import annotations

from evoeye.cli.supervise import default_monitors
from evoeye.monitor.families import initial_monitor
from evoeye.paths import DataRoot


def test_without_monitor_the_scenarios_newest_fusion_monitor_is_the_trigger(tiny, trained,
                                                                             capsys) -> None:
    assert default_monitors(tiny.root, tiny.scenario, None) == [initial_monitor(
        tiny.root, tiny.scenario)]
    assert "the newest FusionMonitor trained on highway-cut-in" in capsys.readouterr().err
    assert default_monitors(tiny.root, tiny.scenario, ["none"]) == []
    assert default_monitors(tiny.root, tiny.scenario, ["fusion-x", "fusion-y"]) == [
        "fusion-x", "fusion-y"]


def test_a_root_without_one_runs_the_baselines_and_says_so(tmp_path, capsys) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    assert default_monitors(root, "unprotected-intersection", None) == []
    assert "no FusionMonitor is trained on unprotected-intersection" in capsys.readouterr().err
