"""The registries of scenarios and baselines: found once, each name once, and bad declarations
refused with one line naming them."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from evoeye.evaluation.baselines import BASELINE_SPECS, BaselineSpec
from evoeye.plugins import Registry, RegistryError, UnknownNameError
from evoeye.scenarios import SCENARIO_SPECS, AuditBands, ScenarioError, ScenarioSpec


def scenarios(group: str = "evoeye.test-none") -> Registry[ScenarioSpec]:
    """A registry of the built-in scenarios and of the entry point group `group`."""
    return Registry("logical scenario", package="evoeye.scenarios.builtin", attr="SCENARIO",
                    group=group, cls=ScenarioSpec)


def test_the_built_ins_are_found_in_their_package_in_name_order() -> None:
    fresh = scenarios()
    assert list(fresh) == list(SCENARIO_SPECS)[:len(fresh)]
    assert list(fresh) == sorted(fresh)  # module name order: highway_cut_in, …
    assert all(spec.world_builder() for spec in fresh.values())  # every path imports
    assert list(BASELINE_SPECS)[:4] == ["ttc", "ttc-2d", "rss", "rss-2s"]  # by `order`


def test_a_name_is_registered_once_and_an_unknown_one_is_named() -> None:
    fresh = scenarios()
    spec = next(iter(fresh.values()))
    assert fresh.register(spec) is spec  # the same declaration again: nothing changes
    with pytest.raises(RegistryError, match=f"logical scenario '{spec.name}' is registered twice"):
        fresh.register(replace(spec, label="another"))
    with pytest.raises(RegistryError, match="a logical scenario must be a ScenarioSpec"):
        fresh.register(spec.space)  # type: ignore[arg-type]
    with pytest.raises(UnknownNameError, match=f"unknown logical scenario 'roundabout'; known: "
                                               f"{', '.join(fresh)}"):
        fresh["roundabout"]
    assert fresh.get("roundabout") is None and "roundabout" not in fresh


def test_an_entry_point_that_declares_nothing_is_refused_by_name(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    dist = tmp_path / "broken-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: broken\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[evoeye.test-broken]\nnothing = os.path:sep\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    fresh = scenarios("evoeye.test-broken")
    for read in (fresh.reload, lambda: list(fresh)):  # every read raises, none half-filled
        with pytest.raises(RegistryError, match=r"entry point nothing = os.path:sep declares "
                                                r"no ScenarioSpec"):
            read()
    monkeypatch.undo()
    fresh.reload()  # the package gone: the registry is whole again
    assert list(fresh) == list(scenarios())


def test_bad_bands_and_baselines_are_refused() -> None:
    with pytest.raises(ScenarioError, match="collision-rate band"):
        AuditBands(collision_rate=(0.6, 0.4))
    with pytest.raises(RegistryError, match="give a rule or a family"):
        BaselineSpec("both", "both", rule=lambda: None, family="aem")
    with pytest.raises(RegistryError, match="give a rule or a family"):
        BaselineSpec("neither", "neither")
