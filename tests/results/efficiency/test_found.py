"""Failures found: collisions per run acquired, per strategy, against Uniform's."""

from __future__ import annotations

import pytest

from evoeye.evaluation.failure_rate import failure_rate
from evoeye.results.efficiency.found import failure_rates, failures_found
from evoeye.results.efficiency.report import found_table


def curve(acquired: dict[int, tuple[int, int]]) -> dict:
    """A stored curve: at each budget, (collisions, runs) acquired beyond the initial set."""
    out = {"budgets": {"40": {"scratch": {}}}}  # the initial set acquires nothing
    for budget, (collided, runs) in acquired.items():
        out["budgets"][str(budget)] = {"scratch": {}, "acquired": {"runs": runs,
                                                                   "collided": collided}}
    return out


def test_collisions_per_run_acquired_are_counted_over_seeds_and_paired_with_uniform() -> None:
    uniform = {"0": curve({80: (1, 40), 320: (8, 280)}),
               "1": curve({80: (2, 40), 320: (12, 280)}),
               "2": curve({80: (0, 40), 320: (10, 280)})}
    boundary = {"0": curve({80: (4, 40), 320: (30, 280)}),
                "1": curve({80: (6, 40), 320: (25, 280)}),
                "2": curve({80: (5, 40), 320: (35, 280)}),
                "7": curve({80: (40, 40), 320: (280, 280)})}  # no Uniform seed to pair with
    found = failures_found({"uniform": uniform, "boundary": boundary}, 320)
    u, b = found["uniform"], found["boundary"]
    assert (u["collisions"], u["runs"], u["seeds"]) == (30, 840, 3)
    assert u["per_run"]["value"] == pytest.approx(30 / 840)
    assert u["per_run"]["low"] < 30 / 840 < u["per_run"]["high"]
    assert b["per_run"]["value"] == pytest.approx(370 / 1120)  # every seed of its own
    assert b["vs_reference"]["ratio"] == pytest.approx((370 / 1120) / (30 / 840))
    paired = b["vs_reference"]["paired"]
    assert paired["n"] == 3  # seed 7 has no Uniform pair
    assert paired["mean_diff"] == pytest.approx((90 - 30) / 280 / 3)
    assert "vs_reference" not in u
    early = failures_found({"uniform": uniform, "boundary": boundary}, 80)
    assert early["uniform"]["per_run"]["value"] == pytest.approx(3 / 120)


def test_the_table_shows_collisions_per_100_runs_and_uniforms_multiple() -> None:
    uniform = {str(s): curve({320: (s, 100)}) for s in range(1, 5)}  # 10 of 400
    boundary = {str(s): curve({320: (3 * s, 100)}) for s in range(1, 5)}  # 30 of 400
    found = {"320": failures_found({"uniform": uniform, "boundary": boundary}, 320)}
    table = "\n".join(found_table(found))
    assert "| uniform (reference) | 2.5 [" in table
    assert "| boundary | 7.5 [" in table and "×3.00" in table


def test_failure_rates_weigh_uniform_by_its_counts_and_a_weighted_strategy_by_its_own() -> None:
    uniform = {str(s): curve({320: (c, 280)}) for s, c in enumerate((2, 4, 3))}
    weighted = {}
    for s, w in enumerate((0.05, 0.04, 0.06)):
        weighted[str(s)] = curve({320: (140, 280)})
        weighted[str(s)]["budgets"]["320"]["acquired"]["failure_rate"] = failure_rate(
            [True] * 140 + [False] * 140, [w] * 140 + [1.0] * 140).to_dict()
    rates = failure_rates({"uniform": uniform, "ce-is": weighted, "boundary": uniform}, 320)
    assert set(rates) == {"uniform", "ce-is"}  # boundary's runs carry no weights: no estimate
    assert rates["uniform"]["mean"] == pytest.approx(9 / 840)
    assert rates["ce-is"]["mean"] == pytest.approx(0.025)  # 140 · 0.05 / 280, on average
    u, c = rates["uniform"], rates["ce-is"]
    assert c["vs_reference"]["relative_error"] == pytest.approx(
        c["relative_error"] / u["relative_error"])
    assert c["relative_error"] < u["relative_error"]


def test_the_rates_table_shows_each_estimate_its_spread_and_uniforms_multiple() -> None:
    from evoeye.results.efficiency.report import rates_table

    rates = {"320": {"uniform": {"mean": 0.01, "spread": 0.6, "relative_error": 0.5},
                     "ce-is": {"mean": 0.011, "spread": 0.2, "relative_error": 0.2,
                               "vs_reference": {"spread": 1 / 3, "relative_error": 0.4}}}}
    table = "\n".join(rates_table(rates))
    assert "| uniform (reference) | 1.00 % (±0.60) |" in table
    assert "| ce-is | 1.10 % (±0.20) ×0.33 |" in table
