"""The testing-efficiency figures on curves whose answers are known by construction."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rare_curves import rare_curves

from evoeye.results.rare.config import RareConfig
from evoeye.results.rare.summary import (
    distinct,
    estimates,
    found,
    found_pooled,
    summarise,
    weights,
)


def curve(hits: list[bool], log_q: list[float | None] | None = None,
          kinds: list[str] | None = None) -> dict:
    n = len(hits)
    log_q = log_q or [None] * n
    kinds = kinds or ["cut-in"] * n
    return {"x": [[0.0]] * n, "log_q": log_q,
            "log_p": [None if q is None else 0.0 for q in log_q],
            "runs": [{"collided": h, "mechanism": k if h else None,
                      "cause": "planning" if h else None}
                     for h, k in zip(hits, kinds, strict=True)]}


def test_weights_are_p_over_q_and_one_for_runs_drawn_from_p():
    c = curve([False, True, False], log_q=[None, math.log(4.0), math.log(0.5)])
    assert weights(c) == pytest.approx([1.0, 0.25, 2.0])


def test_found_counts_per_100_and_the_ratio_to_uniform():
    uniform = {str(s): curve([i == 0 for i in range(100)]) for s in range(4)}  # 1 per 100
    other = {str(s): curve([i < 5 for i in range(100)]) for s in range(4)}  # 5 per 100
    out = found({"uniform": uniform, "ce-is": other})
    assert out["uniform"]["per_100"]["value"] == pytest.approx(1.0)
    assert out["ce-is"]["collisions"] == 20 and out["ce-is"]["runs"] == 400
    vs = out["ce-is"]["vs_reference"]
    assert vs["ratio"] == pytest.approx(5.0)
    assert vs["ratio_low"] == pytest.approx(5.0) and vs["ratio_high"] == pytest.approx(5.0)
    assert vs["paired"]["mean_diff"] == pytest.approx(4.0)


def test_ratio_interval_is_open_above_when_uniform_finds_too_few():
    uniform = {str(s): curve([s == 0 and i == 0 for i in range(50)]) for s in range(6)}
    other = {str(s): curve([i < 3 for i in range(50)]) for s in range(6)}
    vs = found({"uniform": uniform, "ce-is": other})["ce-is"]["vs_reference"]
    assert vs["ratio"] == pytest.approx(18.0)  # 18 / 300 against 1 / 300
    assert vs["ratio_high"] is None  # most resamples lose Uniform's one collision


def test_importance_estimates_are_reweighted_and_compared_at_equal_budget():
    # p = 2 %: Uniform sees it as counts; the IS curves draw failures 10x as often (q/p = 10
    # on them) and hit exactly 20 %, so their estimate is exact at every seed
    rng = np.random.default_rng(0)
    uniform = {str(s): curve(list(rng.random(100) < 0.02)) for s in range(30)}
    is_curves = {str(s): curve([i < 20 for i in range(100)],
                               log_q=[math.log(10.0)] * 20 + [math.log(0.8 / 0.98)] * 80)
                 for s in range(30)}
    out = estimates({"uniform": uniform, "ce-is": is_curves}, runs=100, batch=10)
    assert out["ce-is"]["mean"] == pytest.approx(0.02)
    assert out["ce-is"]["spread"] == pytest.approx(0.0, abs=1e-12)
    # the reference is Uniform's own pooled share, whatever the other strategies estimate
    hits = sum(r["collided"] for c in uniform.values() for r in c["runs"])
    assert out["reference"]["value"] == pytest.approx(hits / 3000)
    assert out["reference"]["low"] < hits / 3000 < out["reference"]["high"]
    p = hits / 3000
    assert out["reference"]["uniform_exact_relative_error"] == pytest.approx(
        math.sqrt((1 - p) / (100 * p)))
    assert out["uniform"]["relative_error"] > 0.3  # binomial noise at 2 per seed
    # every IS seed says 2 %: its error about Uniform's P is that P's own miss, seed by seed
    assert out["ce-is"]["relative_error"] == pytest.approx(abs(0.02 - p) / p)
    assert out["ce-is"]["error_ratio"]["value"] == pytest.approx(
        out["uniform"]["relative_error"] / (abs(0.02 - p) / p))
    closer = out["ce-is"]["paired_abs_error"]
    assert closer["n"] == 30 and closer["mean_diff"] > 0 and closer["ci_low"] > 0
    assert out["ce-is"]["per_seed"]["7"] == pytest.approx(0.02)
    bias = out["ce-is"]["bias_vs_uniform"]
    assert bias["low"] <= bias["diff"] <= bias["high"]


def test_distinct_mechanisms_per_seed_and_overall():
    a = {"0": curve([True, True, False], kinds=["cut-in", "crossing", "x"]),
         "1": curve([True, False, False])}
    u = {"0": curve([True, False, False]), "1": curve([False, False, False])}
    out = distinct({"uniform": u, "ce-is": a})
    assert out["ce-is"]["total"] == 2 and out["ce-is"]["classes"] == 2
    assert out["ce-is"]["per_seed"] == pytest.approx(1.5)
    assert out["ce-is"]["by_mechanism"] == {"cut-in / planning": 2, "crossing / planning": 1}
    assert out["ce-is"]["vs_reference"]["mean_diff"] == pytest.approx(1.0)


def test_summarise_without_curves_is_empty_not_an_error():
    assert summarise({}, RareConfig()) == {"found": {}, "estimates": {}, "distinct": {}}


def test_bias_interval_stays_open_where_uniform_saw_no_failure():
    from evoeye.results.rare.summary import bias

    b = bias(np.array([0.001, 0.002, 0.0015, 0.0005]), hits=0, runs=800)
    # a normal interval for Uniform's 0 / 800 has no width and would call 0.00125 a bias;
    # Wilson's reaches 0.48 %, so the difference's interval holds 0
    assert b["diff"] == pytest.approx(0.00125)
    assert b["low"] < 0 < b["high"]


def test_subset_variants_find_but_do_not_estimate():
    # their levels are not conditional probabilities of p0 where the level is noisy
    # (`evoeye.evolve.search.subset`): they get a failures-found row and no estimate
    hits = {str(s): curve([i < 2 for i in range(50)]) for s in range(3)}
    for c in hits.values():
        for r in c["runs"]:
            r["fitness"] = 0.0 if r["collided"] else 0.5
    curves = {"uniform": hits, "subset": hits, "subset-deep": hits, "subset-spread": hits}
    assert set(found(curves)) == set(curves)
    assert set(estimates(curves, runs=50, batch=10)) == {"reference", "uniform", "subset"}


def test_a_tighter_uniform_rate_narrows_the_ratio_and_moves_it_with_the_pooled_rate():
    curves = rare_curves()  # Uniform: 8 in 4 000 (0.2 %); ce-is: 200 in 4 000 (5 %)
    alone = found(curves)["ce-is"]["vs_reference"]
    pooled = found_pooled(curves, 40_000, 40)  # 48 in 44 000: ≈ 0.109 %
    ref = pooled["reference"]
    assert (ref["runs"], ref["collisions"]) == (44_000, 48)
    assert ref["value"] == pytest.approx(48 / 44_000) and ref["low"] < ref["value"] < ref["high"]
    r = pooled["ce-is"]
    assert r["ratio"] == pytest.approx(0.05 / (48 / 44_000))
    assert r["low"] < r["ratio"] < r["high"]
    # a denominator of 48 collisions, not 8: the interval is far narrower
    assert r["high"] / r["low"] < 0.6 * alone["ratio_high"] / alone["ratio_low"]  # 1.8 vs 3.4
    assert found_pooled(curves, 0, 0) == {}
    assert found_pooled({"ce-is": curves["ce-is"]}, 10, 1) == {}


def test_by_stretch_gives_the_rate_over_each_hundred_runs_of_the_curves():
    late = {str(s): curve([i >= 150 and i % 5 == 0 for i in range(250)]) for s in range(3)}
    out = found({"uniform": late})["uniform"]["by_stretch"]
    assert out == pytest.approx([0.0, 10.0, 20.0])  # 10 of 100, then 10 of the last 50
