"""The context-only control in RQ1: trained on the train runs, calibrated on val, measured on
test, stored and found again like the AEM, and a row of every RQ1 table."""

from __future__ import annotations

import json
import shutil

from evoeye.baselines.context import ContextOnlyMonitor
from evoeye.baselines.families import CONTEXT_ONLY
from evoeye.paths import DataRoot


def test_trained_on_train_runs_scored_on_val_and_test_and_in_every_rq1_table(
        eval_root, splits, monkeypatch, tmp_path) -> None:
    import evoeye.baselines.context as ctx_mod
    from evoeye.baselines.families import fit_context_only
    from evoeye.evaluation.monitors import load_monitors
    from evoeye.evaluation.report import write_report
    from evoeye.evaluation.rq1 import rq1
    from evoeye.store import RunFilter, load_windows

    def ids_of(split: str) -> set[str]:
        runs = RunFilter(logical_scenario="highway-cut-in", split=split, splits=splits)
        return set(load_windows(eval_root, runs, context_len=1).scenario_id.tolist())

    # eval_root is shared: another test may have trained and saved the control already
    shutil.rmtree(CONTEXT_ONLY.versions_dir(eval_root), ignore_errors=True)
    trained_on, scored = [], []
    real_train, real_score = ctx_mod.train_context_only, ContextOnlyMonitor.score
    monkeypatch.setattr(ctx_mod, "train_context_only",
                        lambda w, *a, **k: trained_on.append(w) or real_train(w, *a, **k))
    monkeypatch.setattr(ContextOnlyMonitor, "score",
                        lambda self, w: scored.append(w) or real_score(self, w))
    (report,) = rq1(eval_root, ["highway-cut-in"], baselines=["context-only"], splits=splits,
                    latency=False, store_scores=False)
    (train,) = trained_on
    assert set(train.scenario_id.tolist()) == ids_of("train")
    assert [set(w.scenario_id.tolist()) for w in scored] == [ids_of("val"), ids_of("test")]
    (m,) = report.monitors
    assert m.name == "context-only" and m.frame.frames == len(scored[1])
    # saved and found again by its training key, like the AEM
    again = fit_context_only(eval_root, "highway-cut-in", splits)
    assert len(trained_on) == 1 and again.version == m.version
    assert load_monitors(eval_root, [m.version])[0].version == m.version
    files = write_report(DataRoot.resolve(tmp_path), [report.to_dict()], "ctx")
    for path in (files.markdown, files.html):
        assert "context-only" in path.read_text()
    names = [x["name"] for x in json.loads(files.json.read_text())[0]["monitors"]]
    assert names == ["context-only"]
