"""The RQ2 report: mean ± std per strategy, per-round curves and the blind-spot map."""

from __future__ import annotations

from evoeye.evolve.experiment import html, markdown, table_rows, write_experiment_report


def _m(f1: float) -> dict:
    return {"f1@0.05": f1, "f1@0.01": f1 / 2, "auroc": 0.9, "auprc": f1}


def _run(f1s: list[float]) -> dict:
    return {"rounds": [{"test": _m(f), "hard": _m(f / 2)} for f in f1s], "blind_spots": {
        "names": ["a", "b"], "u0": [0.1, 0.9], "u1": [0.5, 0.2], "feedback": [0.0, 0.4],
        "acquired": [False, True]}}


RESULTS = {"highway-cut-in": {
    "initial": {"test": _m(0.2), "hard": _m(0.0)}, "g0": "fusion-x",
    "uniform": [_run([0.2, 0.3]), _run([0.2, 0.5])],
    "evoeye": [_run([0.2, 0.6]), _run([0.2, 0.6])],
}}


def test_table_reports_mean_and_std_of_the_last_round() -> None:
    rows = {r[0]: r for r in table_rows(RESULTS["highway-cut-in"], ("uniform", "evoeye"))}
    assert rows["uniform"][1] == "40.0 ± 10.0"  # test F1@0.05 of 0.3 and 0.5
    assert rows["evoeye"][1] == "60.0 ± 0.0"
    assert rows["evoeye"][5] == "30.0 ± 0.0"  # hard F1@0.05
    assert rows["initial (G_0)"][5] == "0.0"  # one value: no spread to report


def test_a_single_seed_shows_no_spread() -> None:
    one = {**RESULTS["highway-cut-in"], "uniform": [_run([0.2, 0.3])]}
    rows = {r[0]: r for r in table_rows(one, ("uniform",))}
    assert rows["uniform"][1] == "30.0"


def test_report_files_hold_tables_curves_and_map(tmp_path) -> None:
    md = markdown(RESULTS)
    assert "## highway-cut-in — RQ2" in md and "Evolution ablation" in md
    page = html(RESULTS)
    assert page.count("<svg") == 5  # 4 curves + the blind-spot map
    assert 'data-series="evoeye"' in page
    folder = write_experiment_report(tmp_path, RESULTS, "t")
    assert {p.name for p in folder.iterdir()} == {"rq2.md", "rq2.html", "rq2.json"}
