"""The operating curves from run records: counts, rates per hour of safe driving, the operating
point at a budget and paired bootstrap CIs."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.evaluation.supervision.report import markdown_report
from evoeye.evaluation.supervision.settings import Settings
from evoeye.evaluation.supervision.summary import (
    ROW_FIELDS,
    at_budget,
    resampling_counts,
    summarise_supervision,
    weighted_medians,
)
from evoeye.evaluation.supervision.triggers import TriggerSpec

THRESHOLDS = (0.2, 0.5, 0.9)
SAFE_S = 18.0  # per run: 40 runs → 0.2 h of safe driving


def trigger(name: str, source: str = "baseline") -> TriggerSpec:
    return TriggerSpec(name, source, name, f"{name}-v", THRESHOLDS,
                       ("FPR 0.05", "FPR 0.01", "FPR 0.001"), (0.05, 0.01, 0.001),
                       (0.5, 0.3, 0.1))


def sim(collided: bool, false: int = 0, *, rear: bool = False, fallback_s: float = 2.0,
        lead_s: float | None = None) -> dict:
    # the earlier measure counted twice as many here (half of them justified or idle)
    return {"collided": collided, "struck_from_behind": rear, "false_interventions": false,
            "false_alarms": 2 * false, "interventions": max(2 * false, 1),
            "fallback_s": fallback_s, "duration_s": 20.0,
            "peak_decel_mps2": 6.0, "peak_jerk_mps3": 10.0, "first_lead_s": lead_s}


def record(sid: str, collided0: bool, per_trigger: dict[str, list[dict | None]]) -> dict:
    """A run record; per trigger one entry per threshold: a sim, or None (never alarmed)."""
    triggers = {}
    for name, outcomes in per_trigger.items():
        sims = [o for o in outcomes if o is not None]
        sim_of = [None if o is None else sims.index(o) for o in outcomes]
        triggers[name] = {"version": f"{name}-v", "sims": sims, "sim_of": sim_of,
                          "first_alarm_frame": [None if o is None else 10 for o in outcomes]}
    return {"scenario_id": sid, "status": "ok", "unsupervised": {
        "collided": collided0, "struck_from_behind": False, "duration_s": 20.0,
        "safe_s": SAFE_S + 2.0, "calm_s": SAFE_S, "safe_encounters": 0 if collided0 else 2},
        "triggers": triggers}


@pytest.fixture(scope="module")
def data() -> tuple[Settings, list[dict]]:
    """40 runs, 10 colliding. Fusion: prevents 8 at every threshold, with 4, 1, 0 false
    interventions in all; ttc: prevents 8 / 2 / 0 with 8 / 0 / 0 false ones, and at its
    lowest threshold causes a rear-end collision in a safe run."""
    records = []
    for i in range(40):
        c0 = i < 10
        if c0:
            f = [sim(i >= 8, lead_s=1.0)] * 3
            t = [sim(i >= 8), sim(i >= 2), None]
        else:
            f = [sim(False, 1 if i < 14 else 0), sim(False, 1 if i == 10 else 0), None]
            t = [sim(i == 39, 1 if i < 18 else 0, rear=i == 39), None, None]
        records.append(record(f"r{i:02d}", c0, {"fusion": f, "ttc": t}))
    settings = Settings("highway-cut-in", "b", (trigger("fusion", "version"), trigger("ttc")))
    return settings, records


def test_rows_hold_exactly_the_listed_fields_and_the_counts(data) -> None:
    settings, records = data
    s = summarise_supervision(settings, records, resamples=500)
    assert all(tuple(r) == ROW_FIELDS for r in s["rows"])
    by = {(r["trigger"], r["threshold"]): r for r in s["rows"]}
    assert {r["runs"] for r in s["rows"]} == {40} and s["collisions_unsupervised"] == 10
    assert [by["fusion", t]["collisions_prevented"] for t in THRESHOLDS] == [8, 8, 8]
    assert [by["ttc", t]["collisions_prevented"] for t in THRESHOLDS] == [8, 2, 0]
    assert [by["ttc", t]["collisions_caused"] for t in THRESHOLDS] == [1, 0, 0]
    safe_h = 40 * SAFE_S / 3600
    assert s["safe_h"] == pytest.approx(safe_h)
    assert by["fusion", 0.2]["false_interventions_per_h"] == pytest.approx(4 / safe_h)
    assert by["fusion", 0.5]["false_interventions_per_h"] == pytest.approx(1 / safe_h)
    label_safe_h = 40 * (SAFE_S + 2.0) / 3600  # the earlier measure, its own denominator
    assert s["label_safe_h"] == pytest.approx(label_safe_h) and s["safe_encounters"] == 60
    assert by["fusion", 0.2]["false_alarms_per_h"] == pytest.approx(8 / label_safe_h)
    point = next(p for p in s["points"] if p["trigger"] == "ttc" and p["threshold"] == 0.2)
    assert point["caused_rear_end"] == 1 and point["label"] == "ttc"
    fusion = next(p for p in s["points"] if p["trigger"] == "fusion")
    assert fusion["label"] == "FusionMonitor" and fusion["lead_s"] == 1.0
    assert fusion["false_per_encounter"] == pytest.approx(4 / 60)
    low, high = fusion["false_interventions_poisson_ci"]  # exact: 4 events in safe_h hours
    assert low == pytest.approx(1.0899 / safe_h, rel=1e-3)
    assert high == pytest.approx(10.2416 / safe_h, rel=1e-3)
    lo, hi = fusion["prevented_ci"]
    assert lo <= fusion["prevented_share"] == 0.8 <= hi and lo < hi


def test_at_a_budget_each_trigger_runs_at_its_best_threshold_within_it(data) -> None:
    settings, records = data
    s = summarise_supervision(settings, records, budgets=(5.0, 60.0), resamples=500)
    at = {(r["budget_per_h"], r["trigger"]): r for r in s["at_budget"]}
    # 1 false intervention in 0.2 h is 5/h; fusion prevents as many at its strictest threshold
    # with none (a tie goes to fewer false interventions); ttc's middle one fits 5/h
    assert at[5.0, "fusion"]["threshold"] == 0.9 and at[5.0, "fusion"]["prevented_share"] == 0.8
    assert at[5.0, "fusion"]["false_interventions_per_h"] == 0.0
    assert at[5.0, "ttc"]["threshold"] == 0.5 and at[5.0, "ttc"]["prevented_share"] == 0.2
    assert at[60.0, "ttc"]["threshold"] == 0.2 and at[60.0, "ttc"]["collisions_caused"] == 1
    (d5, d60) = [d for d in s["differences"] if d["b"] == "ttc"]
    assert d5["difference"] == pytest.approx(0.6) and d5["ci"][0] > 0  # paired: it excludes 0
    assert d5["p"] == pytest.approx(2 * 0.5**6)  # McNemar: 6 runs only fusion prevents, 0 ttc
    assert d60["difference"] == pytest.approx(0.0) and d60["p"] == 1.0  # the same 8 runs
    assert s["simulations"]["naive"] == 40 * (1 + 6)


def test_a_budget_no_threshold_meets_means_supervision_off() -> None:
    prevented = np.array([[0.9, 0.5], [0.8, 0.4]])
    fi = np.array([[9.0, 3.0], [0.5, 2.0]])
    np.testing.assert_array_equal(at_budget(prevented, fi, 1.0), [0.0, 0.8])
    np.testing.assert_array_equal(at_budget(prevented, fi, 3.0), [0.5, 0.8])


def test_the_same_records_and_seed_give_the_same_summary(data) -> None:
    settings, records = data
    a = summarise_supervision(settings, records, resamples=300, seed=4)
    b = summarise_supervision(settings, records, resamples=300, seed=4)
    assert a == b
    counts = resampling_counts(40, 300, seed=4)
    assert counts.shape == (300, 40) and (counts.sum(axis=1) == 40).all()


def test_a_resample_s_median_counts_each_run_as_often_as_it_is_drawn() -> None:
    values = np.array([3.0, 1.0, np.nan, 2.0])
    counts = np.array([[1, 1, 1, 1], [0, 0, 4, 0], [3, 1, 0, 0], [0, 2, 0, 1]], float)
    np.testing.assert_array_equal(weighted_medians(values, counts), [2.0, np.nan, 3.0, 1.0])


def test_the_report_leads_with_the_fusion_monitor_against_the_best_rule(data) -> None:
    from evoeye.evaluation.supervision.report import headline, markdown_report

    settings, records = data
    s = summarise_supervision(settings, records, budgets=(5.0, 60.0), resamples=500)
    text = headline(s, 5.0)
    assert "the FusionMonitor prevents 80.0 %" in text and "causes 0 new ones" in text
    assert "best rule-based trigger, ttc, prevents 20.0 %" in text
    assert "Paired difference +60.0 points" in text and "more than every rule-based" in text
    assert "(McNemar p = 0.031)" in text
    md = markdown_report([s])
    assert md.index("FusionMonitor prevents") < md.index("| Trigger |")  # headline first
    assert "### ttc: operating curve" in md


def _with_oracle(records: list[dict]) -> list[dict]:
    """The records with an oracle at τ = 2, 1, 0.5 s (thresholds ascending): it prevents every
    collision from 1 s ahead, none at 0.5 s."""
    out = []
    for r in records:
        c0 = r["unsupervised"]["collided"]
        sims = [sim(False, lead_s=t) for t in (2.0, 1.0)] + [sim(True, lead_s=0.5)]
        oracle = {"version": "oracle-1", "sims": sims if c0 else [],
                  "sim_of": [0, 1, 2] if c0 else [None] * 3,
                  "first_alarm_frame": [10, 30, 40] if c0 else [None] * 3}
        out.append({**r, "triggers": {**r["triggers"], "oracle": oracle}})
    return out


def test_the_oracle_is_the_ceiling_beside_every_trigger(data) -> None:
    from evoeye.evaluation.supervision.triggers import oracle_trigger

    settings, records = data
    oracle = oracle_trigger((0.5, 1.0, 2.0))
    assert oracle.leads_s == (2.0, 1.0, 0.5) and list(oracle.thresholds) == sorted(
        oracle.thresholds)
    with_oracle = Settings(settings.scenario, "b", (*settings.triggers, oracle))
    s = summarise_supervision(with_oracle, _with_oracle(records), budgets=(5.0,), resamples=200)
    assert [(o["lead_s"], o["prevented_share"]) for o in s["oracle"]] == [
        (0.5, 0.0), (1.0, 1.0), (2.0, 1.0)]
    assert "oracle" not in {r["trigger"] for r in s["rows"] + s["at_budget"]}
    assert all(d["b"] != "oracle" for d in s["differences"])
    fusion = next(r for r in s["at_budget"] if r["trigger"] == "fusion")
    # the FusionMonitor leads by 1 s: the oracle prevents all there; at 0.75 s half
    assert fusion["oracle_at_lead"] == 1.0 and fusion["share_of_oracle"] == pytest.approx(0.8)
    from evoeye.evaluation.supervision.summary import oracle_share_at

    assert oracle_share_at(s["oracle"], 0.75) == pytest.approx(0.5)
    assert oracle_share_at(s["oracle"], 0.25) == 0.0 and oracle_share_at([], 1.0) is None


def test_operating_points_are_chosen_on_the_selection_runs_and_reported_on_these(data) -> None:
    settings, records = data
    # on the selection runs the loosest threshold intervenes falsely nowhere: chosen at 5/h
    select = [{**r, "triggers": {n: {**t, "sims": [{**x, "false_interventions": 0}
                                                   for x in t["sims"]]}
                                 for n, t in r["triggers"].items()}} for r in records]
    s = summarise_supervision(settings, records, budgets=(5.0,), resamples=200, select=select)
    assert s["operating_points"] == "validation" and s["selection_runs"] == 40
    fusion = next(r for r in s["at_budget"] if r["trigger"] == "fusion")
    assert fusion["threshold"] == 0.2 and fusion["val_false_interventions_per_h"] == 0.0
    # reported as it is on these runs: over the budget it was chosen for
    assert fusion["false_interventions_per_h"] == pytest.approx(4 / (40 * SAFE_S / 3600))
    leaky = summarise_supervision(settings, records, budgets=(5.0,), resamples=200)
    assert leaky["operating_points"] == "test"
    from evoeye.evaluation.supervision.report import markdown_report

    assert "chosen on 40 other supervised runs" in markdown_report([s])
    hours = 40 * SAFE_S / 3600  # what resolves a budget on them: one there is 5 an hour
    assert s["selection_safe_h"] == pytest.approx(hours)
    assert (f"Their {hours:.2f} h of driving where no intervention was justified make one false "
            f"intervention {1 / hours:.2g} per hour: a budget below that means none there."
            ) in markdown_report([s])
    assert "chosen on these very runs" in markdown_report([leaky])  # and says so
    assert next(r for r in leaky["at_budget"] if r["trigger"] == "fusion")["threshold"] == 0.9


def test_collisions_are_counted_and_prevented_by_mechanism(data) -> None:
    from evoeye.evaluation.supervision.report import markdown_report

    settings, records = data
    kinds = ["braking-lead"] * 5 + ["cut-in"] * 5  # the ten colliding runs, in order
    with_kinds = [{**r, "unsupervised": {**r["unsupervised"], "mechanism": {
        "kind": kinds[i]} if i < 10 else None}} for i, r in enumerate(records)]
    s = summarise_supervision(settings, with_kinds, budgets=(5.0,), resamples=200)
    assert s["mechanisms"] == {"braking-lead": 5, "cut-in": 5}
    fusion = next(r for r in s["at_budget"] if r["trigger"] == "fusion")
    assert fusion["prevented_by_mechanism"] == {"braking-lead": 5, "cut-in": 3}  # runs 0–7
    assert "| braking-lead | 5 | 5 |" in markdown_report([s])


def test_a_second_trained_trigger_is_paired_with_every_rule_too(data) -> None:
    settings, records = data
    # a second monitor that prevents what ttc prevents at every threshold, plus run 1 where
    # ttc prevents nothing, with fusion's false interventions
    two = []
    for r in records:
        second = dict(r["triggers"]["fusion"])
        if r["unsupervised"]["collided"]:
            saves = r["scenario_id"] in ("r01",) or not r["triggers"]["ttc"]["sims"][0]["collided"]
            s = sim(not saves, lead_s=1.0)
            second = {**second, "sims": [s], "sim_of": [0, 0, 0]}
        two.append({**r, "triggers": {**r["triggers"], "m2": second}})
    both = Settings("highway-cut-in", "b", (trigger("fusion", "version"), trigger("ttc"),
                                             trigger("m2", "version")))
    s = summarise_supervision(both, two, budgets=(5.0,), resamples=200)
    pairs = [(d["a"], d["b"]) for d in s["differences"]]
    assert pairs == [("fusion", "ttc"), ("fusion", "m2"), ("m2", "ttc")]  # not m2 − fusion
    at = {r["trigger"]: r["prevented_share"] for r in s["at_budget"]}
    d = s["differences"][2]
    assert d["difference"] == pytest.approx(at["m2"] - at["ttc"]) and d["rule_based"]
    # the headline's sentence and table stay the headline's; the other pair has its own table
    md = markdown_report([s])
    assert "trained − rule-based trigger" in md and "m2 − ttc" in md
