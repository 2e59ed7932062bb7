"""A run's metadata checked against its logical scenario before it may enter the warehouse.

A log whose metadata was edited in place must not be ingested: an unknown logical scenario would
become a partition of its own, a parameter outside its range is not a concrete scenario of the
space, and a forged scenario id could shadow a genuine run (the ledger deduplicates by id).
"""

from __future__ import annotations

import re
from typing import Any

from evoeye.scenarios import ScenarioError, get_scenario
from evoeye.store.records import RunRecordError

# `LogicalScenario.scenario_id` gives `<logical scenario>-<12 hex>`. An id of that form (of any
# scenario) must be the one its vector and seed give; other ids (synthetic logs, hand-made runs,
# tests) cannot collide with a simulated run's id, so they need only be unique.
CANONICAL_ID = re.compile(r".+-[0-9a-f]{12}")


def check_metadata(meta: dict[str, Any]) -> None:
    """RunRecordError naming the first inconsistency of `meta` with its logical scenario."""
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
    expected = space.scenario_id(x, seed)
    if CANONICAL_ID.fullmatch(sid) and sid != expected:
        raise RunRecordError(f"scenario_id {sid} does not match its parameters and seed "
                             f"(they give {expected})")
