"""The results judge monitors through the same code as `evoeye evaluate` and the campaigns, and
get the very figures the separate paths they replaced got (kept below as `_old_*`, verbatim but
for names) on a tiny seeded case: the synthetic root of conftest, FusionMonitors of one epoch."""

from __future__ import annotations

import json

import pytest

from evoeye.evaluation.dataset import narrow
from evoeye.evaluation.harness import evaluate_monitor
from evoeye.evaluation.metrics import Curves, frame_metrics
from evoeye.evaluation.monitors import BASELINES, check_scores, monitor_context_len
from evoeye.evaluation.scenario import Runs, scenario_metrics
from evoeye.evolve.campaign.assess import FPRS, metrics_dict
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.results import units  # not its test_figures by name: pytest would collect it
from evoeye.results.config import ResultsConfig
from evoeye.results.rq2 import G0_RECIPE
from evoeye.results.study import Study

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
