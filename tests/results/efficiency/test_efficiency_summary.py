"""The study's summaries: areas, the budget Uniform needs, paired differences, efficiency."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evoeye.results.efficiency.summary import area, budget_to_reach, efficiency, summarise

BUDGETS = [40, 80, 160, 320]


def curve(values: dict[int, float]) -> dict:
    return {"budgets": {str(b): {"scratch": {"test": {"auprc": v}}} for b, v in values.items()}}


def test_area_is_the_mean_height_on_a_log_budget_axis() -> None:
    flat = np.array([[0.5, 0.5, 0.5, 0.5]])
    assert area(flat, BUDGETS) == pytest.approx([0.5])
    rising = np.array([[0.0, 0.1, 0.2, 0.3]])  # linear in log2(budget): its mean is the middle
    assert area(rising, BUDGETS) == pytest.approx([0.15])


def test_budget_to_reach_interpolates_in_log_budget() -> None:
    mean = np.array([0.2, 0.4, 0.6, 0.8])
    assert budget_to_reach(0.6, mean, BUDGETS) == pytest.approx(160)
    assert budget_to_reach(0.5, mean, BUDGETS) == pytest.approx(2 ** 6.5 * 1.25)  # between
    assert budget_to_reach(0.1, mean, BUDGETS) == 40
    assert math.isnan(budget_to_reach(0.9, mean, BUDGETS))  # never reached


def test_efficiency_is_uniforms_budget_over_the_strategys_and_censored_past_the_curve() -> None:
    rng = np.random.default_rng(0)
    ref_budgets = [*BUDGETS, 640]
    uniform = np.tile([0.2, 0.4, 0.6, 0.8, 1.0], (8, 1)) + rng.normal(0, 1e-3, (8, 5))
    same = efficiency(uniform[:, 3], uniform, ref_budgets, 320, rng)
    assert same["factor"] == pytest.approx(1.0, abs=0.02) and not same["censored"]
    better = efficiency(np.full(8, 0.9), uniform, ref_budgets, 320, rng)
    assert better["factor"] == pytest.approx(2 ** 0.5, rel=0.02)  # half-way 320 → 640: 453
    assert better["low"] <= better["factor"] <= better["high"]
    beyond = efficiency(np.full(8, 1.5), uniform, ref_budgets, 320, rng)
    assert beyond["censored"] and beyond["factor"] == pytest.approx(2.0)


def test_summarise_pairs_each_strategy_with_uniform_seed_by_seed() -> None:
    seeds = list(range(8))
    noise = np.random.default_rng(1).normal(0, 0.01, 8)
    uniform = {str(s): curve({40: 0.2 + n, 80: 0.3 + n, 160: 0.4 + n, 320: 0.5 + n,
                              640: 0.6 + n}) for s, n in zip(seeds, noise, strict=True)}
    better = {str(s): curve({40: 0.2 + n, 80: 0.35 + n, 160: 0.45 + n, 320: 0.55 + n})
              for s, n in zip(seeds, noise, strict=True)}
    out = summarise({"uniform": uniform, "boundary": better}, seeds, 40, [80, 160, 320], [640])
    b = out["strategies"]["boundary"]
    assert b["final_vs_reference"]["mean_diff"] == pytest.approx(0.05)
    assert b["area_vs_reference"]["ci_low"] > 0 and b["area_vs_reference"]["p_value"] < 0.05
    assert b["efficiency"]["factor"] == pytest.approx(2 ** 0.5, rel=0.02)
    assert len(out["strategies"]["uniform"]["mean"]) == 5  # Uniform's curve goes on to 640
    assert "area_vs_reference" not in out["strategies"]["uniform"]


def test_a_seed_missing_from_one_strategy_leaves_that_pair_out() -> None:
    seeds = [0, 1, 2]
    uniform = {str(s): curve({40: 0.2, 80: 0.3, 160: 0.4, 320: 0.5, 640: 0.6}) for s in seeds}
    other = {str(s): curve({40: 0.2, 80: 0.3, 160: 0.4, 320: 0.5}) for s in seeds[:2]}
    out = summarise({"uniform": uniform, "sobol": other}, seeds, 40, [80, 160, 320], [640])
    assert out["strategies"]["sobol"]["area_vs_reference"]["n"] == 2
    assert out["strategies"]["sobol"]["mean"][1]["n"] == 2
