"""The results judge monitors through the same code as `evoeye evaluate` and the campaigns, and
get the very figures the separate paths they replaced got (kept below as `_old_*`, verbatim but
for names) on a tiny seeded case: the synthetic root of conftest, FusionMonitors of one epoch."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pytest

from evoeye.evaluation.dataset import load_split, narrow
from evoeye.evaluation.harness import evaluate_monitor
from evoeye.evaluation.metrics import Curves, frame_metrics
from evoeye.evaluation.monitors import BASELINES, check_scores, monitor_context_len
from evoeye.evaluation.scenario import Runs, scenario_metrics
from evoeye.evolve.campaign.assess import (
    FPRS,
    HARD_SET_FPR,
    Assessor,
    ensure_scored,
    frame_mask,
    hard_set,
    metrics_dict,
    robust_hard_set,
)
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES, load_calibrated
from evoeye.results import units  # not its test_figures by name: pytest would collect it
from evoeye.results.config import ResultsConfig
from evoeye.results.rq2 import G0_RECIPE
from evoeye.results.study import Study
from evoeye.store import Warehouse
from evoeye.store.feedback import RoundMetrics
from evoeye.store.scores import read_scores

SCENARIO = "highway-cut-in"
KS = (1, 3)


def _json(x):
    """As the ledger keeps a unit's output."""
    return json.loads(json.dumps(x, default=float))


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory, results_root_builder) -> Study:
    root = results_root_builder(tmp_path_factory.mktemp("one-path") / "data")
    # windows at L = 7, monitors at L = 5 and 1: every path narrows them
    cfg = ResultsConfig(scenarios=(SCENARIO,), training_seeds=(0, 1, 2), test_runs=0,
                        test_batch="held", epochs=1, patience=1, context_lens=(1, 5, 7))
    return Study(root, cfg)


@pytest.fixture(scope="module")
def g0s(study: Study) -> list[str]:
    """G_0's recipe with each training seed (G_0 first)."""
    return [units.trained_version(study, SCENARIO, DEFAULT_FAMILY, seed=s, **G0_RECIPE)
            for s in study.config.training_seeds]


@pytest.fixture(scope="module")
def short(study: Study) -> str:
    """A FusionMonitor of L = 1: narrower than G_0's windows."""
    return units.trained_version(study, SCENARIO, DEFAULT_FAMILY, seed=0, context_len=1,
                           modules=G0_RECIPE["modules"])


def _old_test_figures(study: Study, scenario: str, monitor) -> dict:
    """`units.test_figures`' unit before it called `harness.score_and_calibrate`."""
    L = monitor_context_len(monitor)
    val, test = study.windows(scenario, "val"), study.windows(scenario, "test")
    s_val = check_scores(monitor, monitor.score(narrow(val.windows, L)), len(val))
    s_test = check_scores(monitor, monitor.score(narrow(test.windows, L)), len(test))
    thr = calibrate_on_validation(s_val, val.windows, FPRS)
    figures = metrics_dict(s_test, test.windows.label, thr)
    figures.update({f"val_fpr@{f}": thr.realised_fpr[f] for f in FPRS})
    return {"test": figures}


def _old_evaluate_monitor(monitor, val, test, runs) -> tuple[dict, list, list]:
    """`harness.evaluate_monitor` before it called `score_and_calibrate` (latency off)."""
    L = monitor_context_len(monitor)
    s_val = check_scores(monitor, monitor.score(narrow(val.windows, L)), len(val))
    s_test = check_scores(monitor, monitor.score(narrow(test.windows, L)), len(test))
    y_test = test.windows.label
    thr = calibrate_on_validation(s_val, val.windows, FPRS)
    result = {
        "name": monitor.name, "version": monitor.version, "context_len": L,
        "thresholds": dict(thr.by_fpr), "val_fpr": dict(thr.realised_fpr),
        "reachable": {f: thr.reachable(f) for f in FPRS},
        "frame": frame_metrics(s_test, y_test, thr, FPRS).to_dict(),
        "scenario": {k: scenario_metrics(s_test, runs, thr, k, FPRS).to_dict() for k in KS},
        "curves": vars(Curves.of(s_test, y_test)),
    }
    return result, s_val.tolist(), s_test.tolist()


def _monitors(study: Study, g0s: list[str], short: str) -> list:
    fusion = FAMILIES[DEFAULT_FAMILY]
    return [BASELINES["ttc"](study.root, SCENARIO, study.splits),
            fusion.load(study.root, g0s[0]), fusion.load(study.root, short)]


def test_rq1_figures_are_the_old_units(study: Study, g0s: list[str], short: str) -> None:
    for monitor in _monitors(study, g0s, short):
        got = units.test_figures(study, SCENARIO, monitor)
        assert got == _json(_old_test_figures(study, SCENARIO, monitor)), monitor.version
        assert 0 < got["test"]["unsafe"] < got["test"]["frames"]  # both classes: rates measured


def test_evaluate_monitor_is_the_old_one_and_agrees_with_the_rq1_unit(
        study: Study, g0s: list[str], short: str) -> None:
    val, test = study.windows(SCENARIO, "val"), study.windows(SCENARIO, "test")
    w = test.windows
    runs = Runs.of(w.scenario_id, w.frame, w.t_s, test.collision_time_s)
    for monitor in _monitors(study, g0s, short):
        result, s_val, s_test = evaluate_monitor(monitor, val, test, runs, fprs=FPRS, ks=KS)
        new = result.to_dict()
        old, old_val, old_test = _old_evaluate_monitor(monitor, val, test, runs)
        assert _json({k: new[k] for k in old}) == _json(old), monitor.version
        assert s_val.tolist() == old_val and s_test.tolist() == old_test
        unit = units.test_figures(study, SCENARIO, monitor)["test"]  # the same figures, one path
        for fpr in FPRS:
            at = new["frame"]["at_fpr"][str(fpr)]
            assert unit[f"f1@{fpr}"] == at["f1"] and unit[f"recall@{fpr}"] == at["recall"]
            assert unit[f"val_fpr@{fpr}"] == new["val_fpr"][str(fpr)]
        assert unit["auroc"] == new["frame"]["auroc"] and unit["auprc"] == new["frame"]["auprc"]


def _old_judge(study: Study, scenario: str, g0s: list[str]) -> dict[str, np.ndarray]:
    """`units.Judge.of`'s masks, before `Assessor` took the robust Hard Set."""
    w = study.windows(scenario, "test").windows
    thresholds = {}
    for version in g0s:
        monitor = load_calibrated(study.root, version)
        ensure_scored(study.root, monitor, scenario, narrow(w, monitor.context_len))
        thresholds[version] = monitor.thresholds.at(HARD_SET_FPR)
    scores = pa.concat_tables([read_scores(study.root, monitor_version=v) for v in g0s])
    kw = {"logical_scenario": scenario, "horizon_s": study.config.horizon_s,
          "splits": study.splits}
    hard = hard_set(Warehouse(study.root), scores, monitor_version=g0s[0],
                    threshold=thresholds[g0s[0]], **kw)
    robust = robust_hard_set(Warehouse(study.root), scores, thresholds=thresholds, **kw)
    return {"test": np.ones(len(w), bool), "hard": frame_mask(hard, w),
            "robust": frame_mask(robust, w)}


def _old_set_figures(study: Study, masks: dict[str, np.ndarray], version: str) -> dict:
    """`units.set_figures`' unit before it called `Assessor.figures`."""
    monitor = load_calibrated(study.root, version)
    w = study.windows(SCENARIO, "test").windows
    scores = check_scores(monitor, monitor.score(narrow(w, monitor.context_len)), len(w))
    return {name: units.set_metrics(scores[m], w.label[m], monitor.thresholds)
            for name, m in masks.items()}


def _old_assessor(study: Study, g0: str, version: str) -> RoundMetrics:
    """A campaign's `Assessor(root, scenario, g0)(version)` before it took the robust set."""
    monitor = load_calibrated(study.root, g0)
    test = load_split(study.root, SCENARIO, "test", study.splits,
                      context_len=monitor.context_len, horizon_s=study.config.horizon_s)
    w = test.windows
    ensure_scored(study.root, monitor, SCENARIO, w)
    hard = frame_mask(hard_set(
        Warehouse(study.root), read_scores(study.root, monitor_version=g0), monitor_version=g0,
        threshold=monitor.thresholds.at(HARD_SET_FPR), logical_scenario=SCENARIO,
        horizon_s=study.config.horizon_s, splits=study.splits), w)
    judged = load_calibrated(study.root, version)
    scores, labels = judged.score(w), w.label
    return RoundMetrics(version, test=metrics_dict(scores, labels, judged.thresholds),
                        hard=metrics_dict(scores[hard], labels[hard], judged.thresholds))


def test_the_results_sets_are_the_old_judges(study: Study, g0s: list[str], short: str) -> None:
    sets = units.judge(study, SCENARIO, g0s)  # first: it writes the G_0s' scores the sets read
    w = study.windows(SCENARIO, "test").windows
    for version in g0s:
        monitor = load_calibrated(study.root, version)
        rows = read_scores(study.root, monitor_version=version).to_pydict()
        stored = dict(zip(zip(rows["scenario_id"], rows["frame"], strict=True), rows["score"],
                          strict=True))
        got = [stored[(s, int(f))] for s, f in zip(w.scenario_id, w.frame, strict=True)]
        np.testing.assert_allclose(got, monitor.score(narrow(w, monitor.context_len)),
                                   atol=1e-6)
    old = _old_judge(study, SCENARIO, g0s)
    assert list(sets.masks) == list(old) == ["test", "hard", "robust"]
    for name, mask in old.items():
        np.testing.assert_array_equal(sets.masks[name], mask, err_msg=name)
    labels = w.label
    assert sets.sizes() == {name: {"frames": int(m.sum()), "unsafe": int(labels[m].sum())}
                            for name, m in old.items()}
    # not a vacuous case: both hard sets hold unsafe frames, and they differ
    assert sets.sizes()["hard"]["unsafe"] > 0 and sets.sizes()["robust"]["unsafe"] > 0
    assert not np.array_equal(old["hard"], old["robust"])
    for version in [*g0s, short]:  # short: L = 1, narrowed from the study's L = 7 windows
        got = units.set_figures(study, sets, version)
        assert got == _json(_old_set_figures(study, old, version)), version
        assert set(got) == {"test", "hard", "robust"} and got["hard"]["frames"] > 0


def test_a_campaigns_assessment_is_the_old_assessors(study: Study, g0s: list[str]) -> None:
    assess = Assessor(study.root, SCENARIO, g0s[0], splits=study.splits,
                      horizon_s=study.config.horizon_s)
    assert list(assess.masks) == ["test", "hard"]  # no re-seeded G_0s: no robust set
    for version in g0s:
        got = assess(version)
        assert got.as_dict() == _old_assessor(study, g0s[0], version).as_dict(), version
        assert got.hard["unsafe"] > 0 and got.hard["f1@0.05"] is not None
    assert assess(g0s[0]).hard["recall@0.05"] == 0.0  # G_0 misses every frame of its own set


def test_a_set_without_unsafe_frames_keeps_its_sizes_only_in_the_results(
        study: Study, g0s: list[str], tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    sets = units.judge(study, SCENARIO, g0s)
    safe = study.windows(SCENARIO, "test").windows.label == 0
    sets.masks["safe"] = safe  # a set with no unsafe frame: its rates are undefined, not 0
    monkeypatch.setattr(study.ledger, "folder", tmp_path)  # judged afresh, not found
    got = units.set_figures(study, sets, g0s[1])
    assert got["safe"] == {"frames": int(safe.sum()), "unsafe": 0}
    assert got["test"]["unsafe"] > 0 and got["test"]["f1@0.05"] is not None
