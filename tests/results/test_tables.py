"""Tables and findings from per-seed figures: the stats module's numbers, verdicts by the rules."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from evoeye.results.findings import FINDINGS, check_findings, check_verdict
from evoeye.results.markdown import diff_cell, mean_cell, pct, table_markdown
from evoeye.results.tables import build_table, build_tables

RNG = np.random.default_rng(5)
N = 8


def _figures(values: list[float | None], set_name: str = "test") -> list[dict]:
    """Per seed, every metric at the value; None: the target FPRs unreachable (and the areas
    undefined, as on a set with one class)."""
    return [{set_name: {"f1@0.05": v, "f1@0.01": v, "auroc": v, "auprc": v,
                        "reachable@0.05": v is not None, "reachable@0.01": v is not None}}
            for v in values]


def _rq1(fusion: list, **others: list) -> dict:
    methods = {"FusionMonitor": {"figures": _figures(fusion)}}
    methods.update({name: {"figures": _figures(v)} for name, v in others.items()})
    return {"seeds": list(range(len(fusion))), "methods": methods}


def test_rows_and_comparisons_are_the_stats_of_the_per_seed_figures() -> None:
    fusion = list(0.6 + 0.05 * RNG.standard_normal(N))
    aem = list(0.3 + 0.05 * RNG.standard_normal(N))
    table = build_table(next(s for s in _specs() if s.id == "rq1"), "s1",
                        _rq1(fusion, aem=aem, ttc=[0.4] * N))
    row = table["rows"][0]["cells"]["test/auroc"]
    low, high = stats.t.interval(0.95, N - 1, loc=np.mean(fusion), scale=stats.sem(fusion))
    assert (row["mean"], row["low"], row["high"]) == pytest.approx((np.mean(fusion), low, high))
    (vs_aem, vs_ttc) = table["comparisons"]
    assert (vs_aem["a"], vs_aem["b"], vs_ttc["b"]) == ("FusionMonitor", "aem", "ttc")
    d = np.array(fusion) - np.array(aem)
    cell = vs_aem["cells"]["test/f1@0.05"]
    assert cell["mean_diff"] == pytest.approx(d.mean())
    assert cell["p_value"] == pytest.approx(stats.wilcoxon(d).pvalue)  # all 8 positive: 2/2^8
    assert cell["ci_low"] > 0 and cell["pairs_needed"] >= 6
    # a rule: the same figure for every seed, shown as one value; its SD plays the part of 0
    ttc = table["rows"][2]["cells"]["test/auroc"]
    assert ttc["sd"] == 0 and mean_cell(ttc, "auroc", N) == "40.0"
    assert vs_ttc["cells"]["test/auroc"]["pairs_needed"] is not None


def test_an_undefined_seed_is_left_out_and_counted() -> None:
    fusion = [0.5, None, 0.6, 0.55, 0.52, 0.58]
    table = build_table(next(s for s in _specs() if s.id == "rq1"), "s1",
                        _rq1(fusion, aem=[0.3] * 6))
    row = table["rows"][0]["cells"]["test/f1@0.05"]
    assert row["n"] == 5 and (row["unreachable"], row["undefined"]) == (1, 0)
    assert mean_cell(row, "f1@0.05", 6).endswith("(1/6 n/r)")
    area = table["rows"][0]["cells"]["test/auroc"]  # undefined, not for want of a threshold
    assert (area["unreachable"], area["undefined"]) == (0, 1)
    assert mean_cell(area, "auroc", 6).endswith("(1/6 undefined)")
    cell = table["comparisons"][0]["cells"]["test/f1@0.05"]
    assert cell["n"] == 5 and cell["undefined"] == 1
    assert diff_cell(cell).endswith("‡")  # 5 pairs: p ≥ 2/2^5 > 0.05
    every = build_table(next(s for s in _specs() if s.id == "rq1"), "s1",
                        _rq1([None] * 6, aem=[0.3] * 6))
    assert mean_cell(every["rows"][0]["cells"]["test/f1@0.05"], "f1@0.05", 6) == "n/r"


def _specs():
    from evoeye.results.tables import TABLES

    return TABLES


def _rq2(values: dict[str, list[float]], k_seeds: list[float]) -> dict:
    methods = {"G_0": {"figures": [{s: {"f1@0.05": 0.2, "f1@0.01": 0.1, "auroc": 0.7,
                                        "auprc": 0.3} for s in ("test", "hard", "robust")}] * N},
               "G_0 (k seeds)": {"figures": [{s: {"f1@0.05": v, "f1@0.01": v, "auroc": v,
                                                  "auprc": v} for s in ("test", "hard", "robust")}
                                             for v in k_seeds], "unpaired": True}}
    for name, vs in values.items():
        methods[name] = {"figures": [{s: {"f1@0.05": v, "f1@0.01": v, "auroc": v, "auprc": v}
                                      for s in ("test", "hard", "robust")} for v in vs]}
    return {"campaign_seeds": list(range(N)), "methods": methods}


def test_rq2_pairs_by_campaign_seed_and_keeps_the_k_seed_control_unpaired() -> None:
    base = 0.3 + 0.03 * RNG.standard_normal(N)
    part = _rq2({"uniform": list(base), "evoeye": list(base + 0.04),
                 "no-feedback": list(base - 0.01)}, [0.25, 0.3, 0.28])
    tables = {t["id"]: t for t in build_tables({"s1": {"rq2": part}})}
    assert set(tables) == {"rq2", "evolution-ablation"}  # no aem-evo rows: no AEM-Evo table
    pairs = {(c["a"], c["b"]) for c in tables["rq2"]["comparisons"]}
    assert pairs == {("evoeye", "uniform"), ("uniform", "G_0"), ("evoeye", "G_0")}
    k = next(r for r in tables["rq2"]["rows"] if r["method"] == "G_0 (k seeds)")
    assert k["unpaired"] and k["cells"]["hard/auprc"]["n"] == 3
    evo = next(c for c in tables["rq2"]["comparisons"] if c["b"] == "uniform")
    assert evo["cells"]["robust/f1@0.05"]["mean_diff"] == pytest.approx(0.04)
    assert evo["cells"]["robust/f1@0.05"]["ci_method"] == "degenerate"  # the same gain each seed
    findings = {f["id"]: f for f in check_findings(list(tables.values()))}
    assert findings["rq2-hard"]["verdict"] == "partly"  # beats uniform; avfuzzer did not run
    assert {c["verdict"] for c in findings["rq2-hard"]["checks"]} == {"reproduces"}
    assert findings["rq3-feedback"]["verdict"] == "reproduces"
    assert findings["rq1-baselines"]["verdict"] == "not run yet"


def test_a_finding_is_owed_its_checks_on_every_scenario_its_part_ran_on() -> None:
    base = 0.3 + 0.03 * RNG.standard_normal(N)
    aem_evo = 0.21 + 0.003 * RNG.standard_normal(N)  # ~1 point over AEM G_0's 0.2: little
    with_aem = _rq2({"evoeye": list(base), "aem-evo": list(aem_evo)}, [0.25, 0.3, 0.28])
    with_aem["methods"]["AEM G_0"] = {"figures": with_aem["methods"]["G_0"]["figures"]}
    without = _rq2({"evoeye": list(base)}, [0.25, 0.3, 0.28])
    one = build_tables({"s1": {"rq2": with_aem}})
    both = build_tables({"s1": {"rq2": with_aem}, "s2": {"rq2": without}})
    assert [t["scenario"] for t in both if t["id"] == "aem-evo"] == ["s1"]  # none on s2
    alone = {f["id"]: f for f in check_findings(one)}["rq3-aem-evo"]
    assert alone["verdict"] == "reproduces" and alone["missing"] == 0
    owed = {f["id"]: f for f in check_findings(both)}["rq3-aem-evo"]
    assert owed["checks"] == alone["checks"] and owed["missing"] == 1
    assert owed["verdict"] == "partly"  # s2 ran RQ2 without AEM-Evo: not "reproduces"


def _cell(diff: float, low: float, high: float, p: float) -> dict:
    return {"mean_diff": diff, "ci_low": low, "ci_high": high, "p_value": p}


@pytest.mark.parametrize(("cell", "kind", "verdict"), [
    (_cell(0.04, 0.01, 0.07, 0.01), "better", "reproduces"),
    (_cell(0.04, 0.01, 0.07, 0.08), "better", "not shown"),  # p above α
    (_cell(0.04, -0.01, 0.07, 0.04), "better", "not shown"),  # CI reaches 0
    (_cell(-0.04, -0.07, -0.01, 0.01), "better", "reversed"),
    (_cell(0.01, -0.02, 0.04, 0.5), "little", "reproduces"),
    (_cell(-0.06, -0.09, -0.03, 0.01), "little", "reproduces"),  # a loss is no gain either
    (_cell(0.08, 0.05, 0.11, 0.01), "little", "does not reproduce"),
    (_cell(0.05, 0.02, 0.08, 0.01), "little", "not shown"),
    (_cell(None, None, None, None), "better", "not shown"),
])
def test_verdicts_follow_the_rules(cell: dict, kind: str, verdict: str) -> None:
    assert check_verdict(cell, kind) == verdict


def test_every_finding_names_a_registered_table() -> None:
    ids = {s.id for s in _specs()}
    assert {f.table for f in FINDINGS} <= ids
    assert {f.kind for f in FINDINGS} == {"better", "little"}


def test_percentages_in_the_tables() -> None:
    assert (pct(0.3124), pct(-0.0312, signed=True), pct(0.05, signed=True)) == (
        "31.2", "−3.1", "+5.0")
    assert pct(-1e-5, signed=True) == "+0.0" and pct(None) == "–"  # no "−0.0"


def test_the_acquisition_table_pairs_what_each_method_acquired_by_campaign_seed() -> None:
    def acquired(collisions: list[float], feedback: list[float | None]) -> list[dict]:
        return [{"runs": 40, "collision_share": c, "near_share": 0.1, "feedback": f}
                for c, f in zip(collisions, feedback, strict=True)]

    uniform_fb = list(0.10 + 0.01 * RNG.standard_normal(N))
    evo_fb = [f + 0.02 + 0.005 * RNG.standard_normal() for f in uniform_fb]
    evo_fb[3] = None  # a campaign whose runs have no stored feedback: left out, and counted
    part = _rq2({"uniform": [0.3] * N, "evoeye": [0.3] * N}, [0.3, 0.3, 0.3])
    part["methods"]["uniform"]["acquisition"] = acquired([0.25] * N, uniform_fb)
    part["methods"]["evoeye"]["acquisition"] = acquired([0.2] * (N - 1) + [None], evo_fb)
    part["methods"]["evoeye"]["acquisition"][-1] = None  # a campaign that acquired nothing
    table = next(t for t in build_tables({"s1": {"rq2": part}}) if t["id"] == "acquisition")
    assert [r["method"] for r in table["rows"]] == ["uniform", "evoeye"]  # no G_0 rows
    evo = table["rows"][1]["cells"]["acquired/feedback"]
    defined = [f for f in evo_fb[:-1] if f is not None]
    assert evo["n"] == N - 2 and evo["undefined"] == 2
    assert evo["mean"] == pytest.approx(np.mean(defined))
    (cmp,) = table["comparisons"]
    assert (cmp["a"], cmp["b"]) == ("evoeye", "uniform")
    diff = np.array([e - u for e, u in zip(evo_fb[:-1], uniform_fb, strict=False)
                     if e is not None])
    cell = cmp["cells"]["acquired/feedback"]
    assert cell["n"] == N - 2 and cell["mean_diff"] == pytest.approx(diff.mean())
    assert cell["p_value"] == pytest.approx(stats.wilcoxon(diff).pvalue)
    collided = cmp["cells"]["acquired/collision_share"]
    assert collided["mean_diff"] == pytest.approx(-0.05)
    assert not any(line.startswith("²") for line in table_markdown(table))
    part["methods"]["aem-evo"] = {**part["methods"]["uniform"]}  # an AEM-scored method
    other = next(t for t in build_tables({"s1": {"rq2": part}}) if t["id"] == "acquisition")
    text = table_markdown(other)
    assert sum("| aem-evo ² |" in line for line in text) == 1
    assert sum(line.startswith("² its f is |score − label| under its own family") for line in
               text) == 1 and not any("| uniform ²" in line for line in text)
