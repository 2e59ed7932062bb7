"""A third party adds a logical scenario and a baseline with one file each, registered through
entry points (a throw-away `*.dist-info`, read by importlib.metadata as pip's would be): no other
file changes, and the whole pipeline sees them — simulate, ingest, the warehouse, and every
list of scenarios and baselines."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from evoeye.evaluation.baselines import BASELINE_SPECS, rule_names
from evoeye.scenarios import SCENARIO_SPECS, SCENARIOS

PLUGINS = Path(__file__).parent / "plugins"  # holds the package evoeye_toy
SCENARIO, BASELINE = "toy-braking-lead", "toy-wide-ttc"
ENTRY_POINTS = """\
[evoeye.scenarios]
braking-lead = evoeye_toy.braking_lead:SCENARIO

[evoeye.baselines]
wide-ttc = evoeye_toy.wide_ttc:BASELINE
"""


def install(site: Path) -> Path:
    """The package's metadata as an installer writes it: a dist-info with its entry points."""
    dist = site / "evoeye_toy-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: evoeye-toy\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(ENTRY_POINTS)
    return site


@pytest.fixture
def installed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    site = install(tmp_path / "site")
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.syspath_prepend(str(PLUGINS))
    SCENARIO_SPECS.reload()
    BASELINE_SPECS.reload()
    yield site
    monkeypatch.undo()
    SCENARIO_SPECS.reload()
    BASELINE_SPECS.reload()
    assert SCENARIO not in SCENARIOS and BASELINE not in BASELINE_SPECS


def test_without_the_entry_points_neither_is_known() -> None:
    assert SCENARIO not in SCENARIOS and BASELINE not in BASELINE_SPECS


def test_every_list_of_scenarios_and_baselines_takes_the_plugins(installed: Path) -> None:
    import numpy as np

    from evoeye.evaluation.audit import bands_of
    from evoeye.evaluation.headline import label, scenario_words
    from evoeye.evaluation.monitors import BASELINES
    from evoeye.results import demo
    from evoeye.results.config import ResultsConfig
    from evoeye.results.efficiency.config import EfficiencyConfig
    from evoeye.sim.runner import world_builder

    assert list(SCENARIOS)[-1] == SCENARIO and SCENARIOS[SCENARIO].dim == 2
    assert SCENARIO in ResultsConfig().scenarios and SCENARIO in EfficiencyConfig().regimes
    assert bands_of(SCENARIO).collision_rate == (0.0, 1.0)
    assert scenario_words(SCENARIO) == f"{SCENARIO} (toy braking lead)"
    space = SCENARIOS[SCENARIO]
    world, cruise_mps = world_builder(SCENARIO)(space.as_dict(space.low), np.random.default_rng(0))
    assert cruise_mps > 0 and world.scene().n >= 2
    assert demo.plan([SCENARIO]) == ([], [SCENARIO])  # no demo monitor shipped: skipped

    assert BASELINE in BASELINES and BASELINE in rule_names()
    assert BASELINE in ResultsConfig().baselines and label(BASELINE) == "TTC (wide corridor)"
    monitor = BASELINES[BASELINE](None, SCENARIO, None)
    assert monitor.name == BASELINE and monitor.corridor_margin_m == 2.0


def _evoeye(site: Path, *args: str) -> subprocess.CompletedProcess:
    path = os.pathsep.join([str(site), str(PLUGINS), os.environ.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-m", "evoeye", *args], capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": path}, timeout=600)


def _unwrapped(help_text: str) -> str:
    """Help text as one line: a name the terminal width broke at a hyphen is whole again."""
    return re.sub(r"\s+", " ", re.sub(r"-\n\s+", "-", help_text))


def test_the_whole_pipeline_runs_a_plugin_scenario_and_lists_the_plugin_baseline(
        tmp_path: Path) -> None:
    site, root = install(tmp_path / "site"), str(tmp_path / "data")
    assert SCENARIO in _unwrapped(_evoeye(site, "simulate", "--help").stdout)
    assert BASELINE in _unwrapped(_evoeye(site, "evaluate", "--help").stdout)
    done = _evoeye(site, "simulate", "--scenario", SCENARIO, "--n", "3", "--root", root)
    assert done.returncode == 0, done.stderr
    assert len(list((tmp_path / "data" / "runs" / SCENARIO).rglob("*.mcap"))) == 3
    assert _evoeye(site, "ingest", "--root", root).returncode == 0
    query = "SELECT logical_scenario, count(*) AS n FROM scenarios GROUP BY 1"
    rows = _evoeye(site, "sql", query, "--root", root, "--format", "csv").stdout
    assert f"{SCENARIO},3" in rows.splitlines()
    demo = _evoeye(site, "demo", "--scenario", SCENARIO, "--root", root)
    assert demo.returncode != 0 and "skipped (no demo monitor shipped" in demo.stderr
    assert "Traceback" not in demo.stderr
