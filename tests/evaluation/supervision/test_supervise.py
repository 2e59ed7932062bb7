"""A supervision end to end on four real runs: calibrated thresholds, one record per run whose
simulations are the unsupervised run until their first alarm, logs with the supervisor's
channels, and a resume that redoes nothing finished and recomputes the same bytes."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from evoeye.batch import plan_uniform, run_batch
from evoeye.evaluation.mechanism import MECHANISMS
from evoeye.evaluation.supervision import check_held_out, supervise
from evoeye.evaluation.supervision.batch import (
    batch_runs,
    plan_supervision,
    record_path,
    run_supervision,
    worker_pool,
)
from evoeye.evaluation.supervision.sweep import (
    ReproductionError,
    RunJob,
    supervise_run,
    supervised_spec,
)
from evoeye.evaluation.supervision.triggers import ORACLE_LEADS_S, realised, sweep_thresholds
from evoeye.log import read_run
from evoeye.store import SplitSpec, Warehouse, ingest

TRIGGERS = [("baseline", "ttc")]


def _supervise(sup):
    return supervise(sup.root, sup.scenario, sup.batch, TRIGGERS, splits=sup.splits,
                     fprs=sup.fprs, logs="all")


@pytest.fixture(scope="module")
def result(sup):
    return _supervise(sup)


def test_every_run_gets_a_record_paired_with_its_logged_outcome(sup, result) -> None:
    trigger, oracle = result.settings.triggers  # the oracle comes with every supervision
    assert trigger.name == "ttc" and list(trigger.thresholds) == sorted(set(trigger.thresholds))
    assert oracle.oracle and oracle.leads_s == tuple(sorted(ORACLE_LEADS_S, reverse=True))
    assert len(result.records) == 4 and not result.errors
    logged = {s.scenario_id: m for s, m in plan_supervision(sup.root, result.settings).runs}
    for r in result.records:
        u, t = r["unsupervised"], r["triggers"]["ttc"]
        assert u["collided"] == logged[r["scenario_id"]]["collided"]
        assert len(t["sim_of"]) == len(t["first_alarm_frame"]) == len(trigger.thresholds)
        for j, (first, sim) in enumerate(zip(t["first_alarm_frame"], t["sim_of"],
                                             strict=True)):
            assert (first is None) == (sim is None)  # no alarm: the unsupervised run
            if sim is not None:
                s = t["sims"][sim]
                assert j in s["thresholds"] and s["first_alarm_frame"] == first
                assert s["interventions"] >= 1 and s["fallback_s"] > 0
        # a lower threshold alarms no later
        frames = [f if f is not None else 10**6 for f in t["first_alarm_frame"]]
        assert frames == sorted(frames)
    assert sum(r["unsupervised"]["collided"] for r in result.records) == 2


def test_the_oracle_engages_tau_before_each_known_collision_and_nowhere_else(result) -> None:
    leads = result.settings.trigger("oracle").leads_s
    for r in result.records:
        u, o = r["unsupervised"], r["triggers"]["oracle"]
        if not u["collided"]:
            assert o["first_alarm_frame"] == [None] * len(leads) and not o["sims"]
            continue
        contact = round(u["collision_time_s"] * 20)
        assert o["first_alarm_frame"] == [contact - round(t * 20) for t in leads]
        assert all(s["true_interventions"] == 1 and s["false_interventions"] == 0
                   and s["first_lead_s"] == pytest.approx(t)
                   for s, t in zip((o["sims"][i] for i in o["sim_of"]), leads, strict=True))
        assert not o["sims"][o["sim_of"][0]]["collided"]  # 3 s ahead prevents it here


def test_each_intervention_is_judged_and_the_earlier_measure_kept(result) -> None:
    for r in result.records:
        u = r["unsupervised"]
        assert 0 <= u["calm_s"] <= u["safe_s"] + 1e-9 and u["safe_encounters"] >= 0
        assert (u["mechanism"] is None) == (not u["collided"])
        assert u["mechanism"] is None or u["mechanism"]["kind"] in MECHANISMS
        for s in r["triggers"]["ttc"]["sims"]:
            judged = (s["true_interventions"] + s["justified_interventions"]
                      + s["false_interventions"] + s["idle_interventions"])
            assert judged <= s["interventions"]  # the rest came late
            assert s["false_alarms"] == (s["justified_interventions"]
                                         + s["false_interventions"] + s["idle_interventions"])


def test_each_simulation_is_logged_with_the_supervisor_channels(sup, result) -> None:
    r = next(r for r in result.records if r["triggers"]["ttc"]["sims"])
    sim = r["triggers"]["ttc"]["sims"][0]
    path = sup.root.path / sim["log"]
    assert result.folder in path.parents  # never where `evoeye ingest` looks
    run = read_run(path)
    states = [m for _, m in run.messages("/supervisor")]
    assert len(states) == round(sim["duration_s"] * 20)
    modes = [s["mode"] for s in states]
    first = sim["first_alarm_frame"]
    assert set(modes[:first]) == {"nominal"} and modes[first] == "braking"
    assert states[first]["alarm"] and not any(s["alarm"] for s in states[:first])
    meta = run.metadata
    assert meta["scenario_id"] == f"{r['scenario_id']}.ttc.t{sim['lead']:02d}"
    assert meta["source"] == "supervised" and meta["batch"] == f"{sup.batch}-supervised"


def test_a_resumed_supervision_skips_finished_runs_and_recomputes_the_same_bytes(
        sup, result) -> None:
    again = _supervise(sup)
    assert again.done_before == 4 and again.records == result.records
    victim = next(r for r in result.records if r["triggers"]["ttc"]["sims"])
    path = record_path(result.folder, victim["scenario_id"])
    logs = [sup.root.path / s["log"] for s in victim["triggers"]["ttc"]["sims"]]
    before = path.read_bytes(), [p.read_bytes() for p in logs]
    path.unlink()
    for p in logs:
        p.unlink()
    redone = _supervise(sup)
    assert redone.done_before == 3
    assert (path.read_bytes(), [p.read_bytes() for p in logs]) == before


def test_a_run_that_does_not_reproduce_its_log_is_an_error(sup, result, tmp_path) -> None:
    spec, meta = plan_supervision(sup.root, result.settings).runs[0]
    bad = RunJob(str(sup.root.path), str(tmp_path), result.settings, spec,
                 {**meta, "collided": not meta["collided"]})
    with pytest.raises(ReproductionError, match="another software version"):
        supervise_run(bad)
    shutil.rmtree(tmp_path, ignore_errors=True)


def test_the_batch_must_be_held_out_of_train_and_validation(sup) -> None:
    check_held_out(sup.root, sup.scenario, sup.batch, sup.splits)  # the batch is not ingested
    ingested = SplitSpec(seed=0, train_frac=0.3, val_frac=0.3)
    with pytest.raises(ValueError, match="not held out"):
        check_held_out(sup.root, sup.scenario, "b000", ingested)


def test_targets_giving_the_same_threshold_are_one_and_recalls_go_beyond() -> None:
    negatives = np.r_[np.zeros(90), np.linspace(0.5, 0.9, 10)]  # 10 % of them above 0
    positives = np.linspace(0.0, 1.0, 21)  # 0.95 and 1.0 lie above every negative
    scores, labels = np.r_[negatives, positives], np.r_[np.zeros(100), np.ones(21)]
    sweep = sweep_thresholds(scores, labels, (0.5, 0.2, 0.1, 0.05), recalls=(0.5, 0.05))
    assert list(sweep) == pytest.approx([0.0, 0.5 + 4 * 0.4 / 9, 0.95])
    # 0.5, 0.2 and 0.1 all give 0.0: the loosest names it; recall 0.5 is below a negative
    assert list(sweep.values()) == ["FPR 0.5", "FPR 0.05", "recall 0.05"]
    fpr, recall = realised(scores, labels, list(sweep))
    assert fpr == (0.1, 0.05, 0.0) and recall[2] == 1 / 21


def test_asked_for_the_logs_go_where_ingest_takes_them_in(new_eval_root, sup) -> None:
    root = new_eval_root()
    run_batch(plan_uniform(sup.scenario, 4, sup.batch_seed, batch=sup.batch)[1:2], root)  # collides
    out = supervise(root, sup.scenario, sup.batch, TRIGGERS, splits=sup.splits, fprs=sup.fprs,
                    logs="all", logs_into_runs=True)
    logs = [s["log"] for r in out.records for s in r["triggers"]["ttc"]["sims"]]
    assert logs and all(p.startswith(f"runs/{sup.scenario}/{sup.batch}-supervised/")
                        for p in logs)
    report = ingest(root)
    ids = {Path(p).stem for p in logs}
    assert ids <= set(report.ingested) and not report.duplicates
    sources = Warehouse(root).sql("SELECT DISTINCT source FROM scenarios WHERE batch = $b",
                                  {"b": f"{sup.batch}-supervised"}).column("source").to_pylist()
    assert sources == ["supervised"]


def test_a_supervised_run_keeps_the_ads_profile_of_its_run(new_eval_root, sup) -> None:
    root = new_eval_root()
    specs = plan_uniform(sup.scenario, 2, sup.batch_seed, batch=sup.batch, ads="cautious")
    run_batch(specs, root)
    runs = batch_runs(root, sup.scenario, sup.batch)
    assert {spec for spec, _ in runs} == set(specs)  # the profile and the ids
    assert {supervised_spec(spec, "ttc", 0).ads for spec, _ in runs} == {"cautious"}


def test_operating_points_are_never_chosen_on_the_batch_reported_on(sup) -> None:
    with pytest.raises(ValueError, match="choose operating points on other runs"):
        supervise(sup.root, sup.scenario, sup.batch, TRIGGERS, splits=sup.splits,
                  fprs=sup.fprs, select_batch=sup.batch)
    with pytest.raises(ValueError, match="not held out"):  # runs the monitors learned from
        supervise(sup.root, sup.scenario, sup.batch, TRIGGERS, splits=sup.splits,
                  fprs=sup.fprs, select_batch="b000")


def test_skip_reports_on_the_runs_after_the_first_and_reuses_their_records(sup, result) -> None:
    order = [s.scenario_id for s, _ in plan_supervision(sup.root, result.settings).runs]
    later = supervise(sup.root, sup.scenario, sup.batch, TRIGGERS, splits=sup.splits,
                      fprs=sup.fprs, logs="all", skip=1, limit=3)
    assert [r["scenario_id"] for r in later.records] == order[1:3]
    assert later.done_before == 2 and later.folder == result.folder  # the same records
    by_id = {r["scenario_id"]: r for r in result.records}
    assert all(r == by_id[r["scenario_id"]] for r in later.records)
    with pytest.raises(ValueError, match="--skip"):
        plan_supervision(sup.root, result.settings, skip=-1)


def test_a_run_list_supervises_only_those_runs_of_the_batch(sup, result) -> None:
    order = [s.scenario_id for s, _ in plan_supervision(sup.root, result.settings).runs]
    some = run_supervision(sup.root, result.settings, ids=[order[3], order[1]])
    assert [r["scenario_id"] for r in some.records] == [order[1], order[3]]  # batch order
    assert some.done_before == 2 and some.folder == result.folder  # the same records
    with pytest.raises(ValueError, match="1 run.s. not in batch sup of highway-cut-in, e.g. x"):
        plan_supervision(sup.root, result.settings, ids=[order[0], "x"])


def test_one_pool_of_workers_serves_two_supervisions_and_stays_open(sup, result) -> None:
    from dataclasses import replace

    order = [s.scenario_id for s, _ in plan_supervision(sup.root, result.settings).runs]
    here = replace(result.settings, logs="none", software_version="pool-a")
    there = replace(here, software_version="pool-b")  # another key: a folder of its own
    with worker_pool(2) as pool:
        a = run_supervision(sup.root, here, workers=2, ids=order[:2], pool=pool)
        b = run_supervision(sup.root, there, workers=2, ids=order[:2], pool=pool)
        assert pool.submit(sum, [1, 2]).result() == 3  # still open
    assert a.errors == b.errors == [] and a.folder != b.folder
    assert a.records == b.records and len(a.records) == 2
    by_id = {r["scenario_id"]: r for r in result.records}  # what the runs gave in-process
    assert [r["unsupervised"] for r in a.records] == [by_id[i]["unsupervised"]
                                                      for i in order[:2]]
