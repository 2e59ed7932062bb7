"""The demo's closed loop: the shipped monitor as the trigger of the production fallback, its
operating point chosen on the validation runs, said in a safety supervisor's terms."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from evoeye.evaluation.supervision.batch import run_supervision
from evoeye.evaluation.supervision.settings import Settings, read_settings
from evoeye.evaluation.supervision.summary import summarise_supervision
from evoeye.evaluation.supervision.triggers import oracle_trigger
from evoeye.paths import DataRoot
from evoeye.results import demo, demo_loop
from evoeye.store import SplitSpec
from tests.evaluation.supervision.test_summary import SAFE_S, THRESHOLDS, record, sim, trigger

LEADS = (0.5, 1.0, 1.5)  # the oracle's; its thresholds ascend, so its sims go 1.5, 1.0, 0.5


def runs(prefix: str, n: int, collided: int, fusion_false: dict[int, int],
         middle_misses: int = 0) -> list[dict]:
    """`n` runs, the first `collided` colliding. The FusionMonitor prevents every collision at
    its lowest threshold, all but the first `middle_misses` at its middle one and none at its
    top one, and brakes falsely in safe run i `fusion_false[i]` times at its lowest threshold;
    TTC-2D prevents every other collision at its lowest threshold only and never brakes
    falsely; the oracle prevents all from 1 s on."""
    out = []
    for i in range(n):
        if i < collided:
            f = [sim(False, lead_s=1.2), sim(i < middle_misses, lead_s=0.8), None]
            t = [sim(i % 2 == 1, lead_s=0.6), None, None]
            o = [sim(False, lead_s=1.5), sim(False, lead_s=1.0), sim(True)]
        else:
            f = [sim(False, fusion_false.get(i, 0)), None, None]
            t, o = [None] * 3, [None] * 3
        out.append(record(f"{prefix}{i:03d}", i < collided,
                          {"fusion": f, "ttc-2d": t, "oracle": o}))
    return out


SETTINGS = Settings("highway-cut-in", "demo", (trigger("fusion", "version"), trigger("ttc-2d"),
                                               oracle_trigger(LEADS)))


def test_the_words_say_what_the_monitor_prevents_at_the_point_chosen_on_validation() -> None:
    # validation: the lowest threshold braked falsely once, so the middle one is chosen; on the
    # test runs alone the lowest would be (it prevents as many with no false intervention there)
    select = runs("v", 10, 4, {6: 1})
    test = runs("t", 30, 8, {})
    s = summarise_supervision(SETTINGS, test, demo_loop.BUDGETS_PER_H, resamples=200,
                              select=select)
    on_test = summarise_supervision(SETTINGS, test, demo_loop.BUDGETS_PER_H, resamples=200)
    chosen = {r["trigger"]: r for r in s["at_budget"] if r["budget_per_h"] == 1.0}
    assert chosen["fusion"]["threshold"] == THRESHOLDS[1]
    assert {r["threshold"] for r in on_test["at_budget"] if r["trigger"] == "fusion"} == {
        THRESHOLDS[0]}  # what a choice on the reported runs would have taken
    s["errors"] = []
    (line,) = demo_loop.loop_words(s)  # ≤ 1 and ≤ 5 alike: one line
    collisions = sum(r["unsupervised"]["collided"] for r in test)
    val_h = len(select) * SAFE_S / 3600
    assert (f"at the threshold chosen on the {len(select)} validation runs for no false "
            f"intervention there (their {val_h:.2f} h of driving where none was justified "
            f"cannot resolve ≤ 1 or ≤ 5 an hour: one false intervention is already "
            f"{1 / val_h:.0f} an hour)") in line
    assert f"used as the trigger of a 9 m/s² emergency brake on the {len(test)} test runs" in line
    calm_h = len(test) * SAFE_S / 3600
    assert (f"the FusionMonitor prevented {collisions} of {collisions} collisions (100 %") in line
    assert (f"and caused none, with 0 false interventions in {calm_h:.2f} h of driving where "
            f"none was justified (0.0 / h, 95 % upper bound {3.689 / calm_h:.1f} / h), warning "
            "a median 0.80 s ahead — the oracle braking 0.80 s ahead prevents") in line
    at_lead = round(100 * np.interp(0.8, (0.0, *LEADS), (0.0, 0.0, 1.0, 1.0)))
    assert f"the oracle braking 0.80 s ahead prevents {at_lead} %" in line
    ttc = collisions // 2
    assert (f"TTC-2D, its threshold chosen the same way, prevented {ttc} of {collisions} "
            f"collisions ({round(100 * ttc / collisions)} %") in line
    assert "too few to call either trigger better" in line  # 8 test collisions


def test_a_budget_the_validation_runs_resolve_is_named_and_the_rest_said_unresolved() -> None:
    # validation: the lowest threshold prevents one more collision than the middle one, with
    # one false intervention: chosen at ≤ 5 an hour, not at ≤ 1
    select = runs("v", 10, 4, {6: 1}, middle_misses=1)
    for r in select:  # 10 runs of 0.05 h each: one false intervention is 2 an hour
        r["unsupervised"]["calm_s"] = 180.0
    s = summarise_supervision(SETTINGS, runs("t", 12, 10, {11: 2}), demo_loop.BUDGETS_PER_H,
                              resamples=200, select=select)
    s["errors"] = []
    assert s["selection_safe_h"] == pytest.approx(0.5)
    assert [demo_loop.resolved(s, b) for b in demo_loop.BUDGETS_PER_H] == [False, True]
    unresolved, five = demo_loop.loop_words(s)
    assert "cannot resolve ≤ 1 an hour: one false intervention is already 2 an hour" in unresolved
    assert "for ≤ 5 false interventions an hour, the FusionMonitor prevented 10 of 10" in five
    assert "with 0 false interventions in" in unresolved  # the middle threshold
    assert "with 2 false interventions in" in five and "Paired difference" in five
    assert re.search(r"exact McNemar p = [0-9.e-]+\.$", five)


def test_a_scenario_the_loop_cannot_measure_says_why() -> None:
    words = demo_loop.loop_words({"scenario": "x", "skipped": "batch demo holds 0 test runs"})
    assert words == ["  In the loop: not measured: batch demo holds 0 test runs."]


def test_the_demo_supervises_its_own_validation_and_test_runs_apart(tmp_path) -> None:
    """Four real highway runs, two validation and two test, the shipped monitor as trigger."""
    from evoeye.batch import plan_uniform, run_batch
    from evoeye.store import ingest

    root = DataRoot.resolve(tmp_path / "data")
    scenario = "highway-cut-in"
    run_batch(plan_uniform(scenario, 4, 0, batch=demo.BATCH), root)
    ingest(root)
    splits = SplitSpec(seed=0, train_frac=0.0, val_frac=0.5)
    ids = demo_loop.split_ids(root, scenario, demo.BATCH, splits)
    assert ids["val"] and ids["test"] and not set(ids["val"]) & set(ids["test"])
    s = demo_loop.supervise_demo(root, scenario, demo.shipped_monitor(root, scenario),
                                 demo.BATCH, splits)
    assert s["errors"] == [] and s["operating_points"] == "validation"
    assert (s["runs"], s["selection_runs"]) == (len(ids["test"]), len(ids["val"]))
    assert s["settings"]["fallback"]["decel_mps2"] == 9.0  # the production fallback
    assert [t["name"] for t in s["settings"]["triggers"]] == ["fusion", "ttc-2d", "oracle"]
    # the validation runs were supervised at every threshold, apart; each reported threshold
    # is the one they alone choose, and the test runs only ran those
    choose = read_settings(Path(s["selection_folder"]))
    assert s["selection_folder"] != s["folder"] and "oracle" not in [t.name for t in
                                                                     choose.triggers]
    val = run_supervision(root, choose, ids=ids["val"])  # done: read back
    assert val.done_before == len(ids["val"])
    alone = summarise_supervision(choose, val.records, demo_loop.BUDGETS_PER_H, resamples=100)
    assert ([(r["trigger"], r["threshold"]) for r in s["at_budget"]]
            == [(r["trigger"], r["threshold"]) for r in alone["at_budget"]])
    for t in s["settings"]["triggers"][:2]:
        picked = {r["threshold"] for r in alone["at_budget"] if r["trigger"] == t["name"]}
        assert set(t["thresholds"]) == (picked - {None} or {choose.trigger(t["name"])
                                                            .thresholds[-1]})
    assert demo_loop.loop_words(s)[0].startswith("  In the loop: used as the trigger of a 9 m/s²")
    files = demo_loop.write_loop_report(tmp_path, [s])
    assert "In the loop" in files.markdown.read_text() and files.json.is_file()


def test_the_demo_summary_carries_the_loop_and_says_where_its_report_is(tmp_path) -> None:
    from tests.results.test_demo_summary import SCENARIO, _report

    s = summarise_supervision(SETTINGS, runs("t", 30, 8, {}), demo_loop.BUDGETS_PER_H,
                              resamples=200, select=runs("v", 10, 4, {6: 1}))
    s["errors"] = []
    result = demo.DemoResult(DataRoot.resolve(tmp_path), [_report(12, 14)], {},
                             tmp_path / "reports" / "demo", loop={SCENARIO: s})
    text = demo.summary_text(result)
    block = text.split("FusionMonitor warned of 12 of 14 collisions")[1].split("\n\n")[0]
    assert demo_loop.loop_words(s)[0] in block.splitlines()  # under its scenario
    assert demo_loop.LOOP_NOTE in text
    assert dict(result.paths())["the monitor in the loop (Markdown, HTML, JSON)"] == (
        tmp_path / "reports" / "demo" / "supervision.html")
    skipped = demo.DemoResult(result.root, result.reports, {})
    assert "In the loop" not in demo.summary_text(skipped)


def test_records_narrowed_to_the_chosen_thresholds_choose_them_again() -> None:
    select = runs("v", 10, 4, {6: 1}, middle_misses=1)
    for r in select:
        r["unsupervised"]["calm_s"] = 180.0  # ≤ 5 resolved: the two budgets choose apart
    plain = Settings("highway-cut-in", "demo", SETTINGS.triggers[:2])
    full = summarise_supervision(plain, select, demo_loop.BUDGETS_PER_H, resamples=1)
    chosen = demo_loop._chosen(plain, select)
    assert chosen == {"fusion": [THRESHOLDS[0], THRESHOLDS[1]], "ttc-2d": [THRESHOLDS[0]]}
    triggers = list(plain.triggers)
    narrow = Settings("highway-cut-in", "demo", tuple(demo_loop.narrowed(t, chosen[t.name])
                                                      for t in triggers))
    assert narrow.trigger("fusion").targets == ("FPR 0.05", "FPR 0.01")
    again = summarise_supervision(narrow, demo_loop.narrowed_records(select, triggers, chosen),
                                  demo_loop.BUDGETS_PER_H, resamples=1)
    key = ("budget_per_h", "trigger", "threshold", "prevented_share", "false_interventions")
    assert [[r[k] for k in key] for r in again["at_budget"]] == [
        [r[k] for k in key] for r in full["at_budget"]]


def test_validation_runs_without_calm_driving_resolve_nothing_and_say_so() -> None:
    select = runs("v", 6, 6, {})  # every validation run collides: no calm driving at all
    for r in select:
        r["unsupervised"]["calm_s"] = 0.0
    s = summarise_supervision(SETTINGS, runs("t", 12, 4, {}), demo_loop.BUDGETS_PER_H,
                              resamples=50, select=select)
    s["errors"] = []
    (line,) = demo_loop.loop_words(s)
    assert ("their 0.00 h of driving where none was justified cannot resolve ≤ 1 or ≤ 5 an "
            "hour: they hold none of it") in line
    # no false-intervention rate on them: no threshold can be chosen, each trigger stays off
    assert ("the FusionMonitor stayed off: none of its thresholds stayed within that on the "
            "validation runs. TTC-2D, its threshold chosen the same way, stayed off") in line
