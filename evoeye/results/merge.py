"""Runs of one regime-by-regime protocol (the sample-efficiency study, the rare-failure
protocol) checked together: `evoeye findings` over several `evoeye results` runs.

Runs whose configs agree but for regimes, seeds and strategies are one protocol (a field added
since a run was recorded reads as its default: the behaviour that run had), and their claims
are checked over all their regimes. Each regime's checks stay paired over its own seeds, so a
regime may have more seeds than another; a regime in two runs of one protocol is refused by
name (which of the two counts would be a choice).
"""

from __future__ import annotations

import json
from collections.abc import Callable

FREE = ("regimes", "seeds", "strategies")  # what the runs of one protocol may differ in


def merge_runs(runs: list[dict], default: dict, check: Callable[[dict], list[dict]],
               error: type[ValueError], *, noun: str, label: str = "",
               free: tuple[str, ...] = ()) -> list[dict]:
    """Runs ({"path", "config", "findings", "regimes"}) as protocols ({"paths", "config",
    "findings"}): a protocol of one run keeps its own findings; a merged one's are
    `check({"regimes": ...})` over every regime, and its config lists each regime's seeds
    (`{regime: seeds}`). `error` names a regime in two runs (`label` + "regime", `noun`: what
    a protocol is called in the message; `free`: further fields its runs may differ in)."""
    groups: dict[str, list[dict]] = {}
    free = (*FREE, *free)
    for run in runs:
        protocol = {k: v for k, v in {**default, **run["config"]}.items() if k not in free}
        groups.setdefault(json.dumps(protocol, sort_keys=True), []).append(run)
    out = []
    for group in groups.values():
        if len(group) == 1:
            out.append({"paths": [group[0]["path"]], "config": group[0]["config"],
                        "findings": group[0]["findings"]})
            continue
        regimes, owner, seeds, strategies = {}, {}, {}, []
        for run in group:
            if not run.get("regimes"):
                raise error(f"{run['path']}: the {noun}'s regimes are missing (it cannot be "
                            f"checked with the {noun}'s other runs)")
            for regime, result in run["regimes"].items():
                if regime in owner:
                    raise error(f"{run['path']}: {label}regime {regime} is also in "
                                f"{owner[regime]}; give each regime of a {noun} from one run "
                                "only")
                owner[regime], regimes[regime] = run["path"], result
                seeds[regime] = run["config"]["seeds"]
            strategies += [s for s in run["config"].get("strategies", []) if s not in strategies]
        config = {**group[0]["config"], "regimes": list(regimes), "strategies": strategies,
                  "seeds": seeds}
        out.append({"paths": [run["path"] for run in group], "config": config,
                    "findings": check({"regimes": regimes})})
    return out
