"""Why the collisions happened, by `evoeye explain`: careful-driver and attribution shares.

Input: rows of `warehouse/queries/audit_attribution.sql` (view run_attribution, where the
credit-split rule lives: one unit per run, split equally among the module oracles that avoid
the collision, 'compound' when none does). This module only sums them over runs.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import asdict, dataclass
from typing import Any

MODULES = ("perception", "prediction", "planning", "control")
CAUSES = (*MODULES, "compound")


@dataclass(frozen=True)
class AttributionSummary:
    """Shares over the explained collision runs of one logical scenario."""

    collision_runs: int  # collision runs audited
    explained_runs: int  # of which explained (every oracle variant stored)
    careful_runs: int  # of which with a careful-driver verdict
    careful_avoidable: float | None  # share the careful driver avoids
    careful_unavoidable: float | None  # 1 − careful_avoidable
    credit_share: dict[str, float]  # cause → share of the credit (sums to 1)
    oracle_avoids: dict[str, float]  # module → share of runs its oracle alone avoids

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def summarise_attribution(rows: list[dict[str, Any]], collision_runs: int
                          ) -> AttributionSummary | None:
    """Sum run_attribution rows (scenario_id, cause, share, careful_driver_avoids); None when no
    run is explained."""
    credit: dict[str, float] = defaultdict(float)
    avoided_by: dict[str, set[str]] = defaultdict(set)
    careful: dict[str, bool | None] = {}
    for r in rows:
        credit[r["cause"]] += r["share"]
        if r["cause"] in MODULES:
            avoided_by[r["cause"]].add(r["scenario_id"])
        careful[r["scenario_id"]] = r["careful_driver_avoids"]
    runs = len(careful)
    if runs == 0:
        return None
    verdicts = [v for v in careful.values() if v is not None]
    avoidable = sum(verdicts) / len(verdicts) if verdicts else None
    return AttributionSummary(
        collision_runs=collision_runs, explained_runs=runs, careful_runs=len(verdicts),
        careful_avoidable=avoidable,
        careful_unavoidable=None if avoidable is None else 1.0 - avoidable,
        credit_share={c: credit.get(c, 0.0) / runs for c in CAUSES},
        oracle_avoids={m: len(avoided_by[m]) / runs for m in MODULES},
    )
