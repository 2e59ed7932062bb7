"""The demo's ending: the headline per scenario, what evolution changed, which figure is which."""

from __future__ import annotations

from dataclasses import replace

import pytest

from evoeye.evaluation.scenario import FalseAlarms, LeadTimes
from evoeye.monitor.pretrained import PACKAGED, install, packaged_cards, packaged_versions
from evoeye.paths import DataRoot
from evoeye.results import demo
from evoeye.store.feedback import RoundMetrics, RoundRow

SCENARIO = "highway-cut-in"


def _report(warned: int, collisions: int) -> dict:
    def monitor(name: str, hit: int) -> dict:
        lead = LeadTimes(hit, collisions, [2.0] * hit, [f"v{i}" for i in range(hit)])
        fa = FalseAlarms(1, 20, 1, 0.1, [1] + [0] * 19, [0.005] * 20)
        return {"name": name, "scenario": {"3": {
            "at_fpr": {"0.05": {"reachable": True}}, "lead_time": {"0.05": lead.to_dict()},
            "false_alarms": {"0.05": fa.to_dict()}}}}

    return {"logical_scenario": SCENARIO, "fprs": [0.05], "ks": [3], "frame_period_s": 0.05,
            "dataset": {"test": {"scenarios": collisions + 20, "violations": collisions},
                        "val": {"scenarios": 24, "violations": 5}},
            "monitors": [monitor("fusion", warned), monitor("ttc", warned // 2)]}


def _rounds() -> list[RoundRow]:
    def metrics(test: float, hard: float) -> RoundMetrics:
        return RoundMetrics("v", test={"f1@0.05": test, "auprc": 0.5},
                            hard={"f1@0.05": hard, "frames": 300, "unsafe": 40})

    return [RoundRow("evo-1", SCENARIO, "evoeye", 0, 0, "fusion-a", [], 30, 0.0, 0.0,
                     metrics(0.6, 0.0)),
            RoundRow("evo-1", SCENARIO, "evoeye", 0, 1, "fusion-b", ["x", "y", "z", "w"], 34,
                     61.5, 3.0, metrics(0.62, 0.25))]


def test_the_summary_answers_how_many_how_early_and_how_many_false_alarms(tmp_path) -> None:
    result = demo.DemoResult(DataRoot.resolve(tmp_path), [_report(12, 14)],
                             {SCENARIO: _rounds()}, tmp_path / "reports" / "demo")
    text = demo.summary_text(result)
    assert "Operating point: each monitor's alarm threshold is set on validation runs" in text
    assert "FusionMonitor warned of 12 of 14 collisions" in text
    assert "a median 2.0 (2.0–2.0) s before the collision" in text
    assert "false alarms per hour of safe driving (1 of 20 safe runs alarmed)" in text
    assert ("Best rule-based baseline (the rule that warned of the most collisions; ties: "
            "fewer false alarms, longer lead), TTC warned of 6 of 14") in text
    assert ("34 test runs, which no monitor trained or was calibrated on: 14 with a collision, "
            "20 collision-free") in text
    assert "; the thresholds were set on 24 other, validation runs." in text
    assert text.splitlines()[4].startswith(
        "highway-cut-in (S1: a highway, a braking lead and cut-ins) — 34 test runs")
    shipped = demo.packaged_cards()["highway-cut-in"]["data"]
    assert (f"trained by `make demo-monitors` on {shipped['train']['runs']} training runs "
            f"(and calibrated on {shipped['val']['runs']} validation runs) of highway-cut-in"
            ) in text
    assert "Verdict: FusionMonitor warns of more collisions than TTC" in text
    assert ("Evolution: 1 round(s) added 4 runs (62 s simulated) and replaced G_0 fusion-a (the "
            "monitor the campaign started from) by fusion-b: Test-Set F1@0.05 60.0 → 62.0 %, "
            "Hard-Set F1@0.05 0.0 → 25.0 %") in text
    assert "Which figure is which" in text and "Fewer than" not in text  # 14 collisions
    assert [w for w, _ in result.paths()][-1] == "this summary"


def test_too_few_collisions_are_said_so_in_the_summary(tmp_path) -> None:
    result = demo.DemoResult(DataRoot.resolve(tmp_path), [_report(2, 2)], {})
    text = demo.summary_text(result)
    assert "2 test collisions: too few to compare" in text and "Evolution:" not in text
    assert f"Fewer than {demo.MIN_COLLISIONS} test collisions in a scenario" in text


TRIGGER_CONFIRMED = ("highway-cut-in", "unprotected-intersection")


def test_a_monitor_is_shipped_per_scenario_and_installs_into_a_root(tmp_path) -> None:
    from evoeye.monitor.families import load_version
    from evoeye.monitor.recipes import COMMAND_RECIPE
    from evoeye.results import demo_monitors
    from evoeye.scenarios import SCENARIO_SPECS

    versions = packaged_versions()
    assert set(versions) == {n for n, s in SCENARIO_SPECS.items() if s.demo_monitor}
    assert versions == {n: demo.shipped_version(n) for n in versions}
    cards = packaged_cards()
    root = DataRoot.resolve(tmp_path)
    for scenario, version in versions.items():
        card = cards[scenario]
        params = card["selection"]["train"]["params"]
        assert (params["train_frac"], params["val_frac"]) == (0.8, 0.2)  # demo_monitors.SPLITS
        assert card["data"]["train"]["runs"] >= 300 and card["parent"] is None
        shipped = card["shipped"]  # which runs trained it: not the demo's (seed, batch)
        assert (shipped["batch"], shipped["simulation_seed"]) == (demo_monitors.BATCH,
                                                                 demo_monitors.SEED)
        assert card["hyperparameters"]["seed"] == shipped["training_seed"] == 0
        if scenario in TRIGGER_CONFIRMED:  # the monitor `evoeye train` makes, where the
            # closed loop confirmed it (docs/lookahead.md)
            assert card["hyperparameters"]["recipe"] == COMMAND_RECIPE
        assert sum(p.stat().st_size for p in (PACKAGED / version).iterdir()) < 400_000
        assert install(root, version) == version == install(root, version)
        monitor = load_version(root, version)  # the weights match the card's sha256
        assert monitor.card["logical_scenario"] == scenario


def test_a_scenario_without_a_shipped_monitor_is_skipped_or_one_clear_error(
        tmp_path, monkeypatch) -> None:
    from evoeye.scenarios import SCENARIO_SPECS, ScenarioError

    monkeypatch.setitem(SCENARIO_SPECS, SCENARIO,
                        replace(SCENARIO_SPECS[SCENARIO], demo_monitor=None))
    with pytest.raises(LookupError, match="make demo-monitors"):
        demo.shipped_monitor(DataRoot.resolve(tmp_path), SCENARIO)
    run, skipped = demo.plan()
    assert skipped == [SCENARIO] and SCENARIO not in run and run
    assert SCENARIO in demo.skipped_line(skipped)
    assert demo.plan([SCENARIO]) == ([], [SCENARIO])
    with pytest.raises(ScenarioError, match="unknown logical scenario 'roundabout'; simulated "):
        demo.plan(["roundabout"])


def test_the_demo_runs_are_never_the_shipped_monitors_training_runs() -> None:
    from evoeye.batch import plan_uniform
    from evoeye.results import demo_monitors

    for scenario in demo.plan()[0]:
        shipped = {s.params for s in plan_uniform(scenario, 500, demo_monitors.SEED,
                                                  batch=demo_monitors.BATCH)}
        fresh = {s.params for s in plan_uniform(scenario, 120, 0, batch=demo.BATCH)}
        assert not shipped & fresh


def test_a_round_that_kept_g0_says_so_not_that_it_replaced_it() -> None:
    from evoeye.evolve.campaign.report import change_words

    g0, round1 = _rounds()
    kept = change_words([g0, replace(round1, monitor_version=g0.monitor_version)])
    assert ("and kept G_0 fusion-a (the monitor the campaign started from; kept: no update beat "
            "it on the validation split).") in kept
    assert "replaced" not in kept and "→" not in kept
    assert ("replaced G_0 fusion-a (the monitor the campaign started from) by fusion-b: "
            "Test-Set F1@0.05 60.0 → 62.0 %") in change_words([g0, round1])
    empty = change_words([g0, replace(round1, monitor_version=g0.monitor_version,
                                      scenario_ids=[])])
    assert "added 0 runs" in empty and "kept: no round acquired a run to learn from)." in empty
