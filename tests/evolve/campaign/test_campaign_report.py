"""The RQ2 report: mean ± sample SD per strategy, CIs as error bars, per-round curves and the
blind-spot map."""

from __future__ import annotations

from html import escape

from evoeye.evolve.campaign.report import (
    OTHER_SCALE_NOTE,
    acquisition_rows,
    html,
    markdown,
    table_rows,
    write_experiment_report,
)
from evoeye.paths import DataRoot


def _m(f1: float) -> dict:
    return {"f1@0.05": f1, "f1@0.01": f1 / 2, "auroc": 0.9, "auprc": f1}


def _run(f1s: list[float], collisions: float = 0.5) -> dict:
    return {"rounds": [{"test": _m(f), "hard": _m(f / 2)} for f in f1s],
            "acquisition": {"runs": 40, "collision_share": collisions, "near_miss_share": 0.1,
                            "near_share": 0.25, "feedback": collisions / 4},
            "blind_spots": {
        "names": ["a", "b"], "u0": [0.1, 0.9], "u1": [0.5, 0.2], "feedback": [0.0, 0.4],
        "acquired": [False, True]}}


RESULTS = {"highway-cut-in": {
    "initial": {"test": _m(0.2), "hard": _m(0.0)}, "g0": "fusion-x",
    "uniform": [_run([0.2, 0.3], 0.2), _run([0.2, 0.5], 0.4)],
    "evoeye": [_run([0.2, 0.6]), _run([0.2, 0.6])],
}}


def test_table_reports_mean_and_sample_sd_of_the_last_round() -> None:
    rows = {r[0]: r for r in table_rows(RESULTS["highway-cut-in"], ("uniform", "evoeye"))}
    assert rows["uniform"][1] == "40.0 ± 14.1"  # test F1@0.05 of 0.3 and 0.5: SD 0.1·√2
    assert rows["evoeye"][1] == "60.0 ± 0.0"
    assert rows["evoeye"][5] == "30.0 ± 0.0"  # hard F1@0.05
    assert rows["initial (G_0)"][5] == "0.0"  # one value: no spread to report


def test_the_reseeded_control_is_a_row_of_its_own() -> None:
    res = {**RESULTS["highway-cut-in"],
           "reseeded": [{"test": _m(0.2), "hard": _m(0.2)}, {"test": _m(0.4), "hard": _m(0.3)}]}
    rows = {r[0]: r for r in table_rows(res, ("uniform",))}
    row = rows["G_0 re-seeded ×2 (no new data)"]
    assert row[1] == "30.0 ± 14.1" and row[5] == "25.0 ± 7.1"
    assert html({"highway-cut-in": res}).count("<svg") == 9  # controls add no chart


def test_aem_evo_is_shown_after_its_own_initial_aem() -> None:
    res = {**RESULTS["highway-cut-in"], "aem-initial": {"test": _m(0.1), "hard": _m(0.3)},
           "aem-evo": [_run([0.1, 0.12]), _run([0.1, 0.16])]}
    rows = table_rows(res, ("evoeye", "aem-evo"))
    assert [r[0] for r in rows] == ["initial (G_0)", "evoeye", "AEM (AEM-Evo's G_0)", "aem-evo"]
    assert rows[2][1] == "10.0" and rows[2][5] == "30.0"  # the AEM G_0's own figures
    assert rows[3][1] == "14.0 ± 2.8"
    assert [r[0] for r in table_rows(RESULTS["highway-cut-in"], ("aem-evo",))] == [
        "initial (G_0)"]  # no AEM campaign ran: no AEM rows


def test_a_single_seed_shows_no_spread() -> None:
    one = {**RESULTS["highway-cut-in"], "uniform": [_run([0.2, 0.3])]}
    rows = {r[0]: r for r in table_rows(one, ("uniform",))}
    assert rows["uniform"][1] == "30.0"


def test_seeds_with_an_unreachable_fpr_are_counted_not_averaged_as_zero() -> None:
    def unreachable(run: dict) -> dict:  # the last round missed FPR 0.01 on both sets
        last = run["rounds"][-1]
        for split in ("test", "hard"):
            last[split] = {**last[split], "f1@0.01": None, "reachable@0.01": False}
        return run

    res = {**RESULTS["highway-cut-in"],
           "uniform": [unreachable(_run([0.2, 0.3])), _run([0.2, 0.5])],
           "evoeye": [unreachable(_run([0.2, 0.6])), unreachable(_run([0.2, 0.6]))]}
    rows = {r[0]: r for r in table_rows(res, ("uniform", "evoeye"))}
    assert rows["uniform"][2] == "25.0 (1/2 n/r)"  # F1@0.01 of the one reachable seed
    assert rows["evoeye"][2] == "n/r" and rows["evoeye"][6] == "n/r"
    assert rows["evoeye"][1] == "60.0 ± 0.0"  # FPR 0.05 was reached
    assert "n/r: the target FPR is unreachable" in markdown({"highway-cut-in": res})
    assert "n/r: the target FPR" not in markdown(RESULTS)


def test_report_files_hold_tables_curves_and_map(tmp_path) -> None:
    md = markdown(RESULTS)
    assert md.startswith("# Self-evolution under the same simulation budget (RQ2)")
    assert "## highway-cut-in: Acquisition methods compared (RQ2), on the Test Set" in md
    assert "## highway-cut-in: Evolution ablation, on the Hard Set of G_0" in md
    assert "| Method | F1@.05 % | F1@.01 % | AUROC % | AUPRC % |" in md
    page = html(RESULTS)
    assert page.count("<svg") == 9  # 4 error-bar charts, 4 curves, the blind-spot map
    assert 'data-series="evoeye"' in page
    # uniform's last-round test F1 over its two seeds, 0.3 and 0.5: mean 40, t CI 40 ± 127.06
    half = 12.706204736174707 * 10.0
    assert f'data-interval="{40 - half:.4g},{40 + half:.4g}"' in page
    assert 'data-estimate="60"' in page and 'data-interval="60,60"' in page  # evoeye: no spread
    folder = write_experiment_report(DataRoot.resolve(tmp_path), RESULTS, "t")
    assert {p.name for p in folder.iterdir()} == {"rq2.md", "rq2.html", "rq2.json"}


def test_acquisition_table_averages_over_seeds() -> None:
    rows = {r[0]: r for r in acquisition_rows(RESULTS["highway-cut-in"])}
    assert set(rows) == {"uniform", "evoeye"}  # strategies that did not run are left out
    assert rows["uniform"] == ["uniform", "40 ± 0", "30.0 ± 14.1", "10.0 ± 0.0", "25.0 ± 0.0",
                               "7.5 ± 3.5"]
    assert "| uniform | 40 ± 0 | 30.0 ± 14.1 |" in markdown(RESULTS)


def test_every_table_fits_the_artifact_view() -> None:
    from evoeye.evolve.campaign.report import _sections

    res = {**RESULTS["highway-cut-in"],
           "reseeded": [{"test": _m(0.2), "hard": _m(0.2)}, {"test": _m(0.4), "hard": _m(0.3)}]}
    sections = list(_sections({"highway-cut-in": res}))
    assert len(sections) == 5  # two tables × two sets, and the acquisition
    for heading, _, table in sections:
        assert table.fits(), (heading, table.width_chars())
    assert OTHER_SCALE_NOTE not in markdown(RESULTS)  # no `<family>-evo` row, no note


def test_a_family_evo_row_is_marked_its_feedback_on_another_scale() -> None:
    acq = {"runs": 40, "collision_share": 0.3, "near_miss_share": 0.1, "near_share": 0.25,
           "feedback": 0.5}
    res = {"evoeye": [{**_run([0.1, 0.2]), "acquisition": acq}],
           "aem-evo": [{**_run([0.1, 0.12]), "acquisition": acq}]}
    rows = [r[0] for r in acquisition_rows(res)]
    assert rows == ["evoeye", "aem-evo ²"]
    md, page = markdown({"s": res}), html({"s": res})
    assert "| aem-evo ² | 40 |" in md and OTHER_SCALE_NOTE in md
    assert "aem-evo ²" in page and escape(OTHER_SCALE_NOTE) in page


def test_acquisition_counts_runs_within_delta_of_an_earlier_record() -> None:
    from types import SimpleNamespace

    import numpy as np

    from evoeye.evolve.campaign.experiment import acquisition
    from evoeye.evolve.search.records import Records
    from evoeye.scenarios import get_scenario

    space = get_scenario("unprotected-intersection")
    u = np.array([[0.1] * space.dim, [0.9] * space.dim,  # D_init
                  [0.25] * space.dim,  # 0.15 from the first record: near
                  [0.5] * space.dim,  # 0.25 from the nearest earlier one (0.25): not near
                  [0.65] * space.dim])  # 0.15 from the acquired [0.5]: near an earlier record
    records = Records(params=space.denormalise(u), feedback=np.zeros(5),
                      collided=np.array([0, 0, 1, 0, 0], bool),
                      fitness=np.array([1.0, 1.0, 0.0, 0.05, 0.4]))  # gaps 0 (hit), 0.5, 4 m
    campaign = SimpleNamespace(space=space, config=SimpleNamespace(delta=0.2))
    state = SimpleNamespace(records=records, n_init=2)
    got = acquisition(campaign, state)
    assert got["runs"] == 3
    assert got["collision_share"] == 1 / 3
    assert got["near_miss_share"] == 1 / 3  # 0.5 m without a collision; 4 m is no near miss
    assert got["near_share"] == 2 / 3


def test_the_feedback_of_acquired_runs_is_read_under_the_monitor_that_chose_them(
        tmp_path) -> None:
    import numpy as np

    from evoeye.evolve.campaign.experiment import chosen_feedback
    from evoeye.store.feedback import FeedbackRows, RoundRow, feedback_of, write_feedback

    root = DataRoot.resolve(tmp_path)

    def rnd(r: int, version: str, ids: list[str]) -> RoundRow:
        return RoundRow("c", "highway-cut-in", "evoeye", 0, r, version, ids, 2 * r, 10.0 * r)

    def store(version: str, values: dict[str, float]) -> None:
        write_feedback(root, FeedbackRows("highway-cut-in", version, "raw",
                                          np.array(list(values), object),
                                          np.array(list(values.values())),
                                          np.ones(len(values), int)))

    rounds = [rnd(0, "g0", []), rnd(1, "g1", ["a", "b"]), rnd(2, "g2", ["c", "d"])]
    store("g0", {"a": 0.2, "b": 0.4, "init": 0.9})  # a, b were chosen under G_0
    store("g1", {"a": 0.0, "b": 0.0, "c": 0.6})  # c under G_1; d failed (no feedback stored)
    store("g2", {"c": 1.0, "d": 1.0})  # after they were chosen: must not count
    def stored(mode: str):  # Campaign.stored_feedback of a campaign in `mode`
        return lambda version: feedback_of(root, version, mode)

    assert chosen_feedback(stored("raw"), rounds) == np.mean([0.2, 0.4, 0.6])
    assert chosen_feedback(stored("prior-corrected"), rounds) is None  # none in that mode
    assert chosen_feedback(stored("raw"), rounds[:1]) is None  # no round acquired anything


def test_map_axes_are_the_parameters_feedback_depends_on_most() -> None:
    import numpy as np

    from evoeye.evolve.campaign.experiment import map_axes

    rng = np.random.default_rng(0)
    u = rng.random((200, 6))
    feedback = 3 * u[:, 4] - u[:, 1] + 0.05 * rng.random(200)  # strongly on 4, then on 1
    feedback[:5] = np.nan  # unscored records are ignored
    assert map_axes(u, feedback) == (4, 1)
    assert map_axes(u, np.zeros(200)) == (0, 1)  # no signal: the first two


def test_a_round_in_one_line_shows_an_unreachable_f1_as_nr() -> None:
    from evoeye.evolve.campaign.experiment import brief
    from evoeye.store.feedback import RoundMetrics

    m = RoundMetrics("fusion-b",
                     test={"f1@0.05": None, "reachable@0.05": False, "auprc": 0.5},
                     hard={"f1@0.05": 0.25, "reachable@0.05": True, "auprc": None})
    assert brief(m) == "test F1@0.05 n/r, AUPRC 50.0 % | hard F1@0.05 25.0 %"
    assert brief(None) == ""


def test_a_figure_no_seed_defines_is_a_dash_without_a_warning() -> None:
    import warnings

    import numpy as np

    def one_class(run: dict) -> dict:  # a Hard Set of one class: no AUROC, AUPRC for any seed
        for r in run["rounds"]:
            r["hard"] = {**r["hard"], "auroc": None, "auprc": None}
        return run

    res = {**RESULTS["highway-cut-in"],
           "uniform": [one_class(_run([0.2, 0.3])), one_class(_run([0.2, 0.5]))]}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # np.nanmean warned 'Mean of empty slice' here
        rows = {r[0]: r for r in table_rows(res, ("uniform",))}
        page = html({"highway-cut-in": res})
    assert rows["uniform"][7:9] == ["–", "–"]  # hard AUROC, AUPRC: undefined, not "nan"
    assert rows["uniform"][5] == "20.0 ± 7.1"  # hard F1@0.05 of 0.15 and 0.25: defined
    assert "hard auprc per round" in page and "nan" not in rows["uniform"]
    gap = acquisition_rows({"uniform": [{"acquisition": {
        "runs": 3, "collision_share": 0.5, "near_miss_share": np.nan, "near_share": 0.0,
        "feedback": None}}] * 2})
    assert gap[0][3] == "–"  # near misses not recorded by any seed
    assert gap[0][5] == "–"  # no feedback stored under the choosing monitors


def _old_mean_std(values: list[float]) -> str:
    """report._mean_std's cell (every seed reachable) before it took finite_mean: np.nanmean."""
    import numpy as np

    from evoeye.evaluation.stats import sample_sd

    a = np.asarray(values, float)
    mean, sd = f"{100 * np.nanmean(a):.1f}", sample_sd(a)
    return mean if sd is None else f"{mean} ± {100 * sd:.1f}"


def test_a_cell_with_a_finite_value_is_the_nanmean_one_it_was() -> None:
    import numpy as np

    from evoeye.evolve.campaign.report import _mean_std

    rng = np.random.default_rng(7)
    for n in range(1, 26):  # up to 25 seeds, some undefined (NaN), at least one defined
        for _ in range(40):
            values = rng.uniform(0, 1, n)
            values[rng.uniform(size=n) < rng.uniform(0, 0.8)] = np.nan
            values[rng.integers(n)] = rng.uniform(0, 1)
            assert _mean_std(list(values)) == _old_mean_std(list(values)), values


def test_the_strategies_beyond_the_paper_are_rows_of_the_rq2_table() -> None:
    res = {"uniform": [_run([0.3])], "sobol": [_run([0.35])], "boundary": [_run([0.4])],
           "disagreement": [_run([0.45])], "evoeye-knn": [_run([0.2])]}
    md = markdown({"highway-cut-in": res})
    rq2 = md.split("## highway-cut-in: Acquisition methods compared (RQ2)")[1].split("##")[0]
    for name in ("sobol", "boundary", "disagreement", "evoeye-knn"):
        assert f"| {name} |" in rq2
    assert [r[0] for r in acquisition_rows(res)][:1] == ["uniform"]
    assert {r[0] for r in acquisition_rows(res)} == set(res)
