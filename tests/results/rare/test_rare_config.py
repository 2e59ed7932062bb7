"""The testing protocol's config: what it refuses, and how it round-trips."""

from __future__ import annotations

import pytest

from evoeye.results.rare.config import RareConfig


@pytest.mark.parametrize("bad, match", [
    ({"strategies": ("ce-is",)}, "include 'uniform'"),
    ({"strategies": ("uniform", "boundary")}, "need a monitor"),
    ({"seeds": (0,)}, "at least 2 distinct seeds"),
    ({"runs": 30, "batch": 20}, "whole batches"),
    ({"regimes": ("a:b:c",)}, "SCENARIO:PROFILE"),
    ({"data_seed": -1}, "data_seed"),
])
def test_bad_configs_are_refused_with_their_reason(bad, match):
    with pytest.raises(ValueError, match=match):
        RareConfig(**bad)


def test_unknown_profile_is_named():
    with pytest.raises(ValueError, match="no-such"):
        RareConfig(regimes=("highway-cut-in:no-such",)).check_names()


def test_round_trip_and_changed_fields():
    c = RareConfig(seeds=(3, 4), runs=40)
    assert RareConfig.from_dict(c.changed()) == c
    assert c.changed() == {"seeds": [3, 4], "runs": 40}
    with pytest.raises(ValueError, match="unknown rare-failure config"):
        RareConfig.from_dict({"rns": 3})
