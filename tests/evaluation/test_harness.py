"""evaluate(): calibration on val, figures on test, scores stored once, reports rendered."""

from __future__ import annotations

import json
import re
import shutil
from dataclasses import replace

import numpy as np
import pyarrow.parquet as pq
import pytest

from evoeye.baselines import RSSMonitor, TTCMonitor
from evoeye.baselines.aem import AEMConfig
from evoeye.baselines.families import AEM, fit_aem
from evoeye.evaluation import evaluate
from evoeye.evaluation.dataset import load_split
from evoeye.evaluation.headline import label
from evoeye.evaluation.monitors import baseline_monitors
from evoeye.evaluation.report import html_report, markdown_report, write_report
from evoeye.evaluation.rq1 import rq1_report
from evoeye.paths import DataRoot
from evoeye.store import RunFilter
from evoeye.store.attribution import AttributionRow, write_attribution
from evoeye.store.scores import read_scores, scores_dir, scores_schema

SCENARIO = "highway-cut-in"  # the scenario of eval_root (conftest)


@pytest.fixture(scope="module")
def report(eval_root, splits):
    return evaluate(eval_root, [TTCMonitor(), RSSMonitor()], SCENARIO, splits)


def test_metrics_use_frames_before_the_collision_only(report, eval_root, splits,
                                                      layout) -> None:
    test = load_split(eval_root, SCENARIO, "test", splits)
    stats = report.dataset["test"]
    n_viol, after = stats["violations"], layout.n_frames - layout.collision_frame
    assert stats["frames"] == stats["scenarios"] * layout.n_frames - n_viol * after
    assert stats["unsafe_frames"] == n_viol * 3 * layout.rate_hz  # H = 3 s before the collision
    assert report.monitors[0].frame.frames == stats["frames"] == len(test)
    assert (test.windows.t_s < test.collision_time_s - 1e-6).all()


def test_thresholds_come_from_validation(report) -> None:
    for m in report.monitors:
        for fpr, realised in m.val_fpr.items():
            assert realised <= fpr
        assert m.thresholds[0.01] >= m.thresholds[0.05]
        assert set(m.scenario) == {1, 3}


def test_scores_are_stored_once_per_version_and_run(report, eval_root, splits) -> None:
    again = evaluate(eval_root, [TTCMonitor(), RSSMonitor()], SCENARIO, splits)
    assert [m.scores_written for m in again.monitors] == [0, 0]
    n = len(load_split(eval_root, SCENARIO, "val", splits)) + len(
        load_split(eval_root, SCENARIO, "test", splits))
    for m in report.monitors:
        rows = read_scores(eval_root, monitor_version=m.version)
        assert rows.num_rows == n  # val + test, every frame once
        keys = set(zip(rows.column("scenario_id").to_pylist(), rows.column("frame").to_pylist(),
                       strict=True))
        assert len(keys) == n
    for part in scores_dir(eval_root).glob("*.parquet"):
        assert pq.read_schema(part).remove_metadata().equals(scores_schema(), check_metadata=False)


def test_stored_scores_are_the_monitors_scores(report, eval_root, splits) -> None:
    test = load_split(eval_root, SCENARIO, "test", splits, context_len=1)
    expected = TTCMonitor().score(test.windows)
    rows = read_scores(eval_root, monitor_version=TTCMonitor().version).to_pydict()
    stored = {(s, f): v for s, f, v in zip(rows["scenario_id"], rows["frame"], rows["score"],
                                           strict=True)}
    got = [stored[(s, int(f))] for s, f in zip(test.windows.scenario_id, test.windows.frame,
                                               strict=True)]
    assert np.allclose(got, expected, atol=1e-6)


def test_report_dict_is_json(report) -> None:
    d = json.loads(json.dumps(report.to_dict()))
    assert [m["name"] for m in d["monitors"]] == ["ttc", "rss"]
    assert d["monitors"][0]["frame"]["at_fpr"]["0.05"]["tp"] == report.monitors[0].frame.at_fpr[
        0.05].tp


def test_html_report_is_self_contained_with_every_monitors_curves(report, eval_root) -> None:
    d = report.to_dict()
    html = html_report([d])
    assert not re.search(r"https?://|\bsrc=|<script|<link|url\(|@import", html)
    for m in d["monitors"]:
        assert html.count(f'data-series="{label(m["name"])}"') == 2  # ROC and PR
    assert "ROC" in html and "Precision-recall" in html and "Warning lead time" in html
    files = write_report(eval_root, [d], "t-html")
    assert files.html.read_text().startswith("<!DOCTYPE html>")
    assert files.markdown.read_text() == markdown_report([d])
    assert json.loads(files.json.read_text())[0]["logical_scenario"] == SCENARIO


def test_the_report_shows_root_cause_shares_once_runs_are_explained(report, eval_root) -> None:
    assert "Root causes" not in rq1_report(eval_root, [report], "t-no-causes").markdown.read_text()
    variants = ("careful_driver", "oracle_perception", "oracle_prediction", "oracle_planning",
                "oracle_control")
    write_attribution(eval_root, [
        AttributionRow(SCENARIO, "x-1", "v", v, v != "oracle_prediction", None, None, None)
        for v in variants
    ])
    files = rq1_report(eval_root, [report], "t-causes")
    md = files.markdown.read_text()
    assert "## Root causes (evoeye explain)" in md
    row = next(line for line in md.splitlines() if line.startswith("| v |"))
    assert row.split(" | ")[1:7] == ["1", "0.0", "100.0", "0.0", "0.0", "0.0"]
    assert "0/1 (0.0 %)" in row  # the careful driver collided too
    assert "Root causes" in files.html.read_text()
    assert json.loads(files.json.read_text())[0]["attribution"][0]["runs"] == 1


def test_aem_is_trained_once_and_evaluated(eval_root, splits) -> None:
    small = AEMConfig(hidden=(32,), latent=4, epochs=3)
    first = fit_aem(eval_root, SCENARIO, splits, small)
    again = fit_aem(eval_root, SCENARIO, splits, small)
    assert again.version == first.version
    assert (AEM.version_dir(eval_root, first.version) / "model.pt").is_file()
    assert len(list(AEM.versions_dir(eval_root).iterdir())) == 1
    rep = evaluate(eval_root, [first], SCENARIO, splits, store_scores=False)
    assert rep.monitors[0].context_len == 5 and rep.monitors[0].scores_written == 0
    assert rep.monitors[0].frame.auroc is not None


def test_a_trained_baseline_fits_per_seed_and_on_the_runs_asked(eval_root, splits,
                                                                tmp_path) -> None:
    root = DataRoot.resolve(tmp_path / "copy")
    shutil.copytree(eval_root.path, root.path)
    small = AEMConfig(hidden=(16,), latent=4, epochs=2)
    before = set(AEM.versions(root))
    zero = fit_aem(root, SCENARIO, splits, small)
    one = fit_aem(root, SCENARIO, splits, small, seed=1)
    assert one.version != zero.version and one.config.seed == 1
    assert fit_aem(root, SCENARIO, splits, small, seed=1).version == one.version  # found again
    assert fit_aem(root, SCENARIO, splits, small, seed=0).version == zero.version
    train = RunFilter(logical_scenario=SCENARIO, split="train", splits=splits)
    fewer = fit_aem(root, SCENARIO, splits, small, runs=replace(train, collided=True))
    meta = AEM.read_meta(root, fewer.version)
    assert 0 < meta["train_scenarios"] < AEM.read_meta(root, zero.version)["train_scenarios"]
    assert set(AEM.versions(root)) - before == {zero.version, one.version, fewer.version}


def test_baselines_by_name(eval_root, splits) -> None:
    ttc, rss = baseline_monitors(eval_root, SCENARIO, splits, ["ttc", "rss"])
    assert (ttc.name, rss.name) == ("ttc", "rss")
    with pytest.raises(KeyError, match="unknown baseline"):
        baseline_monitors(eval_root, SCENARIO, splits, ["ttc", "nope"])


def test_bad_monitor_scores_are_refused(eval_root, splits) -> None:
    class Broken:
        name, version, context_len = "broken", "broken-0", 1

        def score(self, windows):
            return np.full(len(windows), 2.0)

    with pytest.raises(ValueError, match=r"outside \[0, 1\]"):
        evaluate(eval_root, [Broken()], SCENARIO, splits, store_scores=False)


def test_an_unreachable_fpr_is_reported_as_such_never_as_zero(eval_root, splits) -> None:
    class Saturated:
        """Scores every frame 1.0 but the last tenth of each run: the top score ties for far
        more than 5 % of the negatives, so neither target FPR can be met with any alarm."""
        name, version, context_len = "saturated", "saturated-0", 1

        def score(self, windows):
            return np.where(windows.t_s % 5.0 < 4.5, 1.0, 0.5)

    d = evaluate(eval_root, [Saturated()], SCENARIO, splits, store_scores=False).to_dict()
    m = d["monitors"][0]
    assert m["reachable"] == {"0.05": False, "0.01": False}
    assert m["thresholds"]["0.05"] == 1.0 and m["val_fpr"]["0.05"] == 0.0
    for level in (m["frame"], m["scenario"]["1"]):
        point = level["at_fpr"]["0.05"]
        assert point["reachable"] is False and point["f1"] is None and point["recall"] is None
    md = markdown_report([d])
    headline, per_frame, *_ = (x for x in md.splitlines() if x.startswith("| saturated |"))
    assert headline.count("| n/r ") == 5  # warned, recall, lead, false alarms, safe runs
    assert per_frame.count("| n/r ") == 6 and "| 0.0 |" not in per_frame  # P, R, F1 × 2 FPRs
    assert "n/r: the target FPR is unreachable" in md
    assert "0.0 n/r" in next(x for x in md.splitlines() if x.startswith("| saturated | sat"))
    assert "n/r" in html_report([d])


def test_the_realised_fpr_sits_next_to_its_target(report) -> None:
    md = markdown_report([report.to_dict()])
    assert "| thr@.05 | val FPR@.05 % | thr@.01 | val FPR@.01 % |" in md
    ttc = report.monitors[0]
    line = next(x for x in md.splitlines() if x.startswith(f"| TTC | {ttc.version} |"))
    assert f"| {100 * ttc.val_fpr[0.05]:.1f} |" in line


def test_every_report_table_fits_the_artifact_view(report) -> None:
    from evoeye.evaluation.headline import headline_table
    from evoeye.evaluation.report import dataset_table, monitors_table, rq1_tables

    d = report.to_dict()
    tables = [headline_table(d), dataset_table([d]), monitors_table([d]),
              *(t for _, t in rq1_tables(d))]
    for table in tables:
        assert table.fits(), (table.header, table.width_chars())


def test_the_headline_counts_match_the_run_level_figures(report) -> None:
    d = report.to_dict()
    for m in d["monitors"]:
        sc = m["scenario"]["3"]
        at, lead, fa = sc["at_fpr"]["0.05"], sc["lead_time"]["0.05"], sc["false_alarms"]["0.05"]
        assert lead["detected"] == at["tp"] and lead["violations"] == at["tp"] + at["fn"]
        assert fa["alarmed_runs"] == at["fp"] and fa["safe_runs"] == at["fp"] + at["tn"]
        assert fa["events"] >= fa["alarmed_runs"]
        assert fa["safe_h"] > 0 and d["frame_period_s"] == pytest.approx(0.05)
