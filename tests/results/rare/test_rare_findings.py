"""The rare-failure claims: each check's verdict from its figures, each claim's over the regimes,
and runs of one protocol merged regime by regime."""

from __future__ import annotations

import pytest
from rare_curves import COMMON, RARE, rare_part

from evoeye.results.findings import AGAINST, NOT_RUN, NOT_SHOWN, PARTLY, REPRODUCES
from evoeye.results.rare.findings import (
    RareMergeError,
    estimate_verdict,
    found_target,
    found_verdict,
    merge_rare,
    reference_rate,
)


def _by_id(findings: list[dict]) -> dict[str, dict]:
    return {f["id"]: f for f in findings}


def test_the_target_is_ten_where_failures_are_rarer_than_three_per_mille():
    assert found_target(0.001) == 10.0 and found_target(0.0029) == 10.0
    assert found_target(0.003) == 3.0 and found_target(0.01) == 3.0
    assert found_target(None) == 10.0  # nothing seen: the stricter one


@pytest.mark.parametrize("low, high, verdict", [
    (10.0, 40.0, REPRODUCES), (9.9, 40.0, NOT_SHOWN), (9.9, None, NOT_SHOWN),
    (None, None, NOT_SHOWN), (2.0, 9.9, AGAINST)])
def test_a_ratio_reproduces_only_when_its_whole_interval_reaches_the_target(low, high, verdict):
    assert found_verdict({"ratio_low": low, "ratio_high": high}, 10.0) == verdict


@pytest.mark.parametrize("bias, ratio, verdict", [
    ((-1e-4, 1e-4), (3.0, 9.0), REPRODUCES),
    ((1e-5, 1e-4), (3.0, 9.0), AGAINST),  # biased, however precise
    ((-1e-4, 1e-4), (1.5, 2.9), AGAINST),  # unbiased, not 3x better
    ((-1e-4, 1e-4), (2.0, 9.0), NOT_SHOWN),
    ((-1e-4, 1e-4), (None, None), NOT_SHOWN),
    ((float("nan"), float("nan")), (3.0, 9.0), NOT_SHOWN),  # one seed left: no variance
])
def test_an_estimate_must_be_unbiased_and_three_times_closer(bias, ratio, verdict):
    row = {"bias_vs_uniform": {"diff": 0.0, "low": bias[0], "high": bias[1]},
           "error_ratio": {"value": None, "low": ratio[0], "high": ratio[1]}}
    assert estimate_verdict(row, uniform_failures=8) == verdict
    if verdict != AGAINST or ratio[1] >= 3.0:  # with no failure Uniform's 0 judges no bias
        assert estimate_verdict(row, uniform_failures=0) == NOT_SHOWN


def test_checks_carry_their_paired_cell_target_and_verdict(two_regimes):
    f = _by_id(two_regimes["findings"])
    found = {c["regime"]: c for c in f["rare-found"]["checks"]}
    rare, common = found[RARE], found[COMMON]
    assert rare["strategy"] == "ce-is" and rare["target"] == 10.0
    assert rare["reference_rate"] == pytest.approx(0.002)
    assert rare["ratio"] == pytest.approx(25.0)  # 10 per 200 against 8 per 4000
    assert rare["ratio_low"] >= 10.0 and rare["verdict"] == REPRODUCES
    assert rare["cell"]["n"] == 20 and rare["cell"]["ci_low"] > 0  # per-seed Δ per 100 runs
    assert rare["cell"]["mean_diff"] == pytest.approx(5.0 - 0.2)
    assert common["strategy"] == "sobol" and common["target"] == 3.0
    assert common["ratio_high"] == pytest.approx(1.0) and common["verdict"] == AGAINST
    (estimate,) = f["rare-estimate"]["checks"]  # Sobol carries no p/q: no estimate
    assert estimate["strategy"] == "ce-is" and estimate["regime"] == RARE
    assert estimate["bias"]["low"] < 0 < estimate["bias"]["high"]
    assert estimate["error_ratio"]["low"] >= 3.0 and estimate["verdict"] == REPRODUCES
    assert estimate["cell"]["n"] == 20 and estimate["cell"]["ci_low"] > 0  # closer per seed
    # one strategy reproduces in one regime of two: partly
    assert f["rare-found"]["verdict"] == PARTLY and f["rare-estimate"]["verdict"] == PARTLY


def test_a_claim_reproduces_when_one_strategy_does_in_every_regime():
    part = rare_part({RARE: "rare", COMMON: "rare"})
    assert [f["verdict"] for f in part["findings"]] == [REPRODUCES, REPRODUCES, NOT_RUN]
    flat = rare_part({COMMON: "common"}, strategies=("uniform", "sobol"))
    f = _by_id(flat["findings"])
    assert f["rare-found"]["verdict"] == AGAINST  # every check against
    assert f["rare-estimate"] == {"id": "rare-estimate", "claim": f["rare-estimate"]["claim"],
                                  "checks": [], "verdict": NOT_RUN}  # no estimating strategy


def test_a_strategy_that_ran_but_could_not_be_checked_is_not_shown():
    part = rare_part({RARE: "blind"})
    f = _by_id(part["findings"])
    assert f["rare-found"]["checks"][0]["ratio_low"] is None  # Uniform found none: open
    assert f["rare-found"]["verdict"] == NOT_SHOWN
    assert reference_rate(part["regimes"][RARE]) is None  # Uniform saw none: unknown


def _run(path: str, regimes: dict, **config) -> dict:
    return {"path": path, **rare_part(regimes, **config)}


def test_runs_of_one_protocol_are_checked_over_all_their_regimes():
    a = _run("a.json", {RARE: "rare"})
    b = _run("b.json", {COMMON: "rare"})
    alone = merge_rare([a])
    assert alone[0]["paths"] == ["a.json"] and alone[0]["findings"] == a["findings"]
    (merged,) = merge_rare([a, b])
    assert merged["paths"] == ["a.json", "b.json"]
    assert merged["config"]["seeds"] == {RARE: list(range(20)), COMMON: list(range(20))}
    assert [f["verdict"] for f in merged["findings"]] == [REPRODUCES, REPRODUCES, NOT_RUN]
    learned = _run("e.json", {COMMON: "rare"}, learn={})  # its learning side: still one protocol
    assert [m["paths"] for m in merge_rare([a, learned])] == [["a.json", "e.json"]]
    other = _run("c.json", {RARE: "rare"}, runs=400)  # another protocol
    assert [m["paths"] for m in merge_rare([a, b, other])] == [["a.json", "b.json"],
                                                               ["c.json"]]
    with pytest.raises(RareMergeError, match=f"d.json: rare-failure regime {RARE} is also in "
                                             "a.json"):
        merge_rare([a, b, _run("d.json", {RARE: "rare"})])


def test_advice_names_a_strategy_only_where_it_was_shown_better(two_regimes):
    from evoeye.results.rare.findings import advice
    from evoeye.results.rare.report import rare_findings_markdown

    rows = advice(two_regimes["findings"])
    assert rows[RARE] == {"find": "ce-is", "estimate": "ce-is"}
    # Sobol's ratio to Uniform reaches at most 1: keep Uniform there, for both
    assert rows[COMMON] == {"find": "uniform", "estimate": "uniform"}
    text = rare_findings_markdown(two_regimes["findings"])
    assert f"* `{RARE}`: to find failures, **ce-is**" in text
