"""A run's metadata checked against its logical scenario before it may enter the warehouse.

A log whose metadata was edited in place must not be ingested: an unknown logical scenario would
become a partition of its own, a parameter outside its range is not a concrete scenario of the
space, and a forged scenario id could shadow a genuine run (the ledger deduplicates by id).
Nor may a run another minor release of evoeye wrote: its parameters and its stack mean other
things (docs/warehouse.md), though its schema may be the same.
"""

from __future__ import annotations

import re
from typing import Any

from evoeye.ads.profiles import DEFAULT_PROFILE
from evoeye.scenarios import ScenarioError, get_scenario
from evoeye.sim.worlds import DEFAULT_WORLD, run_variant
from evoeye.store.records import RunRecordError

# `LogicalScenario.scenario_id` gives `<logical scenario>-<12 hex>`. An id of that form (of any
# scenario) must be the one its vector and seed give; other ids (synthetic logs, hand-made runs,
# tests) cannot collide with a simulated run's id, so they need only be unique.
CANONICAL_ID = re.compile(r".+-[0-9a-f]{12}")
# a release's version; other strings (synthetic or hand-made logs) are not an evoeye release's
RELEASE = re.compile(r"(\d+)\.(\d+)\.\d+.*")


def check_version(meta: dict[str, Any]) -> None:
    """RunRecordError if `meta` was written by an evoeye release of another minor version."""
    from evoeye import __version__  # looked up on first use (it costs start-up time)

    written = str(meta.get("software_version"))
    theirs, ours = RELEASE.fullmatch(written), RELEASE.fullmatch(__version__)
    if theirs and ours and theirs.groups() != ours.groups():
        raise RunRecordError(
            f"written by evoeye {written}: runs of {'.'.join(theirs.groups())} cannot be mixed "
            f"with those of {'.'.join(ours.groups())} (the same parameters and seed give other "
            "runs; docs/warehouse.md) — simulate it again into a data root of this version")


def check_metadata(meta: dict[str, Any]) -> None:
    """RunRecordError naming the first inconsistency of `meta` with its logical scenario (or
    with this evoeye's version)."""
    check_version(meta)
    try:
        space = get_scenario(str(meta.get("logical_scenario")))
    except ScenarioError as e:
        raise RunRecordError(str(e)) from None
    names = tuple(str(n) for n in meta.get("param_names") or ())
    if names != space.names:
        raise RunRecordError(f"param_names {list(names)} are not those of {space.name} "
                             f"({list(space.names)})")
    try:
        x = space.validate([float(v) for v in meta.get("params") or ()])
        seed = int(meta["seed"])
    except (ScenarioError, TypeError, ValueError, KeyError) as e:
        raise RunRecordError(f"run metadata does not fit its logical scenario: {e}") from None
    sid = str(meta.get("scenario_id"))
    profile = str(meta.get("ads_profile") or DEFAULT_PROFILE)
    world = str(meta.get("world") or DEFAULT_WORLD)
    expected = space.scenario_id(x, seed, run_variant(profile, world))
    if CANONICAL_ID.fullmatch(sid) and sid != expected:
        raise RunRecordError(f"scenario_id {sid} does not match its parameters and seed "
                             f"(they give {expected})")
