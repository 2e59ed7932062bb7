"""`evoeye results` end to end on a tiny root (3 training seeds, 2 campaign seeds, one-run
campaigns over 2 worker processes): every table carries CIs and p-values computed from the
per-seed figures, and a re-run redoes nothing."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats
from sklearn.metrics import roc_auc_score
from typer.testing import CliRunner

import evoeye.cli.results  # noqa: F401  (registers the command)
from evoeye.cli import app
from evoeye.evaluation.dataset import load_split, narrow
from evoeye.monitor.families import load_version
from evoeye.paths import DataRoot
from evoeye.results.markdown import README_BEGIN, README_END
from evoeye.store import SplitSpec
from evoeye.store.feedback import read_rounds

# its module fixtures are built once only if its tests share a worker (pytest-xdist
# --dist loadgroup); spread over two, each worker builds them again
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("results-end-to-end")]
RUNNER = CliRunner()
SCENARIO = "highway-cut-in"
METHODS = ("uniform", "evoeye", "no-feedback", "aem-evo")  # a row in every RQ2 table
TRAINING_SEEDS, CAMPAIGN_SEEDS = 3, 2  # k = 2 final seeds: fewer than the training seeds


def _args(root: DataRoot, docs: Path, readme: Path) -> list[str]:
    args = ["results", "--root", str(root.path), "--scenario", SCENARIO, "--training-seeds",
            str(TRAINING_SEEDS), "--campaign-seeds", str(CAMPAIGN_SEEDS), "--final-seeds", "2",
            "--test-runs", "0",
            "--test-batch", "held", "--epochs", "1", "--patience", "1", "--budget-s", "20",
            "--n-round", "1", "--context-len", "1", "--context-len", "5", "--inputs",
            "perception", "--inputs", "all", "--name", "tiny", "--docs", str(docs),
            "--readme", str(readme), "--workers", "2"]
    for m in METHODS:
        args += ["--method", m]
    return args


def _state(root: DataRoot) -> dict[str, float]:
    """Every file a re-run must leave alone (monitor versions, campaign state, the ledger) and
    its modification time."""
    out = {}
    for folder in ("monitors", "baselines", "results/ledger", "warehouse/campaign_rounds",
                   "warehouse/feedback", "runs"):
        for path in sorted((root.path / folder).rglob("*")):
            if path.is_file():
                out[str(path.relative_to(root.path))] = path.stat().st_mtime_ns
    return out


@pytest.fixture(scope="module")
def done(tmp_path_factory: pytest.TempPathFactory, results_root_builder) -> SimpleNamespace:
    base = tmp_path_factory.mktemp("results")
    root = results_root_builder(base / "data")
    readme, docs = base / "README.md", base / "docs"
    readme.write_text(f"# x\n\nbefore\n{README_BEGIN}\nold text\n{README_END}\nafter\n")
    first = RUNNER.invoke(app, _args(root, docs, readme))
    assert first.exit_code == 0, first.output
    folder = root.path / "reports" / "tiny"
    before = _state(root)
    first_json = (folder / "results.json").read_bytes()
    second = RUNNER.invoke(app, _args(root, docs, readme))
    assert second.exit_code == 0, second.output
    return SimpleNamespace(root=root, folder=folder, docs=docs, readme=readme, first=first,
                           second=second, before=before, after=_state(root),
                           first_json=first_json, results=json.loads(first_json))


def _table(results: dict, table_id: str) -> dict:
    return next(t for t in results["tables"] if t["id"] == table_id)


def test_every_table_is_made_with_a_ci_and_p_for_every_comparison(done) -> None:
    tables = {t["id"]: t for t in done.results["tables"]}
    assert set(tables) == {"rq1", "ablation", "rq2", "evolution-ablation", "aem-evo",
                           "acquisition"}
    acquired = {r["method"]: r["cells"] for r in tables["acquisition"]["rows"]}
    assert list(acquired) == ["uniform", "evoeye", "no-feedback", "aem-evo"]
    for cells in acquired.values():  # each campaign's runs, scored by the monitor that chose them
        assert cells["acquired/feedback"]["n"] == CAMPAIGN_SEEDS
        assert 0.0 <= cells["acquired/feedback"]["mean"] <= 1.0
    rq1 = tables["rq1"]
    assert [r["method"] for r in rq1["rows"]] == ["FusionMonitor", "ttc", "ttc-2d", "rss",
                                                  "rss-2s", "aem", "context-only",
                                                  "where-when"]
    assert [r["method"] for r in tables["rq2"]["rows"]] == ["G_0", "G_0 (k seeds)", "uniform",
                                                            "evoeye"]
    assert {(c["a"], c["b"]) for c in tables["rq2"]["comparisons"]} == {
        ("evoeye", "uniform"), ("uniform", "G_0"), ("evoeye", "G_0")}
    assert {(c["a"], c["b"]) for c in tables["evolution-ablation"]["comparisons"]} >= {
        ("evoeye", "no-feedback")}
    assert [(c["a"], c["b"]) for c in tables["aem-evo"]["comparisons"]] == [("aem-evo",
                                                                            "AEM G_0")]
    assert tables["rq2"]["sets"] == ["test", "hard", "robust"]
    text = (done.folder / "rq1.md").read_text() + (done.folder / "rq2.md").read_text()
    for table in tables.values():
        for comparison in table["comparisons"]:
            for cell in comparison["cells"].values():
                if cell["n"]:  # a figure undefined for a seed leaves that pair out
                    pairs = TRAINING_SEEDS if table["id"] in ("rq1", "ablation") else CAMPAIGN_SEEDS
                    assert cell["p_value"] is not None and cell["n"] == pairs
            row = f"| {comparison['a']} − {comparison['b']} |"
            assert row in text, row
    assert "p=" in text and "[95 % CI]" in text


def _signed(x: float) -> str:
    return f"{100 * x:+.1f}".replace("-", "−")


def test_a_comparison_recomputed_with_scipy_is_the_one_in_the_table(done) -> None:
    rq1 = done.results["scenarios"][SCENARIO]["rq1"]["methods"]
    fusion = np.array([f["test"]["auroc"] for f in rq1["FusionMonitor"]["figures"]])
    aem = np.array([f["test"]["auroc"] for f in rq1["aem"]["figures"]])
    d = fusion - aem
    assert np.all(d != 0) and d[0] != d[1]  # two distinct pairs: BCa or percentile, exact p
    p = stats.wilcoxon(d, method="exact").pvalue
    cell = next(c for c in _table(done.results, "rq1")["comparisons"]
                if c["b"] == "aem")["cells"]["test/auroc"]
    ci = stats.bootstrap((d,), np.mean, confidence_level=0.95, n_resamples=9999,
                         method=cell["ci_method"], rng=np.random.default_rng(0)
                         ).confidence_interval
    assert cell["ci_method"] in ("BCa", "percentile")
    assert (cell["mean_diff"], cell["p_value"]) == (pytest.approx(d.mean()), pytest.approx(p))
    assert (cell["ci_low"], cell["ci_high"]) == (pytest.approx(ci.low), pytest.approx(ci.high))
    expected = f"{_signed(d.mean())} [{_signed(ci.low)}, {_signed(ci.high)}] p={p:.2g}‡"
    line = next(x for x in (done.folder / "rq1.md").read_text().splitlines()
                if x.startswith("| FusionMonitor − aem |"))
    assert line.split(" | ")[3] == expected  # F1@0.05, F1@0.01, AUROC
    # the row's Student-t interval over the training seeds
    low, high = stats.t.interval(0.95, len(fusion) - 1, loc=fusion.mean(),
                                 scale=stats.sem(fusion))
    row = next(x for x in (done.folder / "rq1.md").read_text().splitlines()
               if x.startswith("| FusionMonitor |"))
    pct = lambda x: f"{100 * x:.1f}".replace("-", "−")  # noqa: E731
    assert row.split(" | ")[3] == f"{pct(fusion.mean())} [{pct(low)}, {pct(high)}]"


def test_a_per_seed_figure_is_the_monitors_own(done) -> None:
    rq1 = done.results["scenarios"][SCENARIO]["rq1"]["methods"]["FusionMonitor"]
    monitor = load_version(done.root, rq1["versions"][1])
    assert monitor.card["hyperparameters"]["seed"] == 1
    test = load_split(done.root, SCENARIO, "test", SplitSpec(**done.results["splits"]),
                      context_len=monitor.context_len)
    assert set(test.windows.scenario_id.tolist()) == {f"held-{i:02d}" for i in range(8)}
    scores = monitor.score(narrow(test.windows, monitor.context_len))
    assert rq1["figures"][1]["test"]["auroc"] == pytest.approx(
        roc_auc_score(test.windows.label, scores))


def test_each_final_monitor_is_the_mean_over_k_training_seeds(done) -> None:
    rq2 = done.results["scenarios"][SCENARIO]["rq2"]
    for method in METHODS:
        row = rq2["methods"][method]
        for campaign, versions in zip(row["campaigns"], row["versions"], strict=True):
            last = read_rounds(done.root, campaign)[-1]
            assert last.round == 1 and versions[0] == last.monitor_version
            assert len(set(versions)) == 2  # the last update again, with another seed
    # the robust Hard Set's re-seeded G_0s: G_0's recipe with the first k of the 3 training
    # seeds, which here (RQ1 on the study's data) are RQ1's FusionMonitors of those seeds
    fusion = done.results["scenarios"][SCENARIO]["rq1"]["methods"]["FusionMonitor"]
    assert rq2["reseeded"] == fusion["versions"][:2] and rq2["g0"] == fusion["versions"][0]
    sets = rq2["sets"]
    assert sets["test"]["frames"] > sets["robust"]["frames"] and sets["robust"]["unsafe"] > 0
    assert sets["hard"]["unsafe"] <= sets["test"]["unsafe"]


def test_the_campaigns_ran_side_by_side_on_the_held_out_test_set(done) -> None:
    campaigns = len(METHODS) * CAMPAIGN_SEEDS
    # each reported by the worker pool once it ended (a campaign run in-process is not)
    assert done.first.output.count("1 round(s) run, budget spent") == campaigns
    assert done.second.output.count("0 round(s) run, budget spent") == campaigns
    assert done.results["splits"]["test_batch"] == "held"
    for method in METHODS:  # every round assessed by its worker on the held-out batch's windows
        for campaign in done.results["scenarios"][SCENARIO]["rq2"]["methods"][method][
                "campaigns"]:
            metrics = read_rounds(done.root, campaign)[-1].metrics
            assert metrics.test["frames"] == done.results["scenarios"][SCENARIO]["rq2"][
                "sets"]["test"]["frames"]


def test_a_rerun_reuses_every_unit(done) -> None:
    assert "0 done now (nothing new)" in done.second.output
    assert "done now (nothing new)" not in done.first.output
    assert done.after == done.before  # no version trained, no campaign round, no ledger entry
    assert (done.folder / "results.json").read_bytes() == done.first_json


def test_docs_readme_and_html_come_from_the_same_results(done) -> None:
    assert sorted(p.name for p in done.docs.iterdir()) == ["findings.md", "results.json",
                                                           "rq1-f1.svg", "rq1.md", "rq2.md"]
    readme = done.readme.read_text()
    assert "before" in readme and "after" in readme and "old text" not in readme
    assert f"Generated by `evoeye results` from {done.docs / 'results.json'}." in readme
    for finding in done.results["findings"]:
        assert finding["claim"] in readme
        if finding["id"] == "rq3-density":  # no-density did not run
            assert finding["verdict"] == "not run yet" and not finding["checks"]
        else:
            assert finding["verdict"] in {"reproduces", "does not reproduce", "partly",
                                          "not shown"} and finding["checks"]
    html = (done.folder / "results.html").read_text()
    cell = next(r for r in _table(done.results, "rq1")["rows"]
                if r["method"] == "FusionMonitor")["cells"]["test/f1@0.05"]
    assert not math.isclose(cell["low"], cell["high"])
    assert f'data-interval="{100 * cell["low"]:.4g},{100 * cell["high"]:.4g}"' in html
    assert html.count("<svg") >= 2 * len(done.results["tables"])


@pytest.fixture(scope="module")
def retrained(done) -> SimpleNamespace:
    """RQ2 judged again with `--final retrain`, on the same campaigns."""
    args = [a for a in _args(done.root, done.docs, done.readme) if a not in ("--docs", "--readme",
            str(done.docs), str(done.readme))]
    args[args.index("--name") + 1] = "retrain"
    run = RUNNER.invoke(app, [*args, "--part", "rq2", "--final", "retrain"])
    assert run.exit_code == 0, run.output
    again = RUNNER.invoke(app, [*args, "--part", "rq2", "--final", "retrain"])
    return SimpleNamespace(run=run, again=again, results=json.loads(
        (done.root.path / "reports" / "retrain" / "results.json").read_text()))


def test_retrain_finals_are_g0s_recipe_on_each_campaigns_data(done, retrained) -> None:
    rq2 = retrained.results["scenarios"][SCENARIO]["rq2"]["methods"]
    before = done.results["scenarios"][SCENARIO]["rq2"]["methods"]
    assert rq2["G_0 (k seeds)"] == before["G_0 (k seeds)"]  # the row it is compared with
    g0_seeds = [load_version(done.root, v).card for v in rq2["G_0 (k seeds)"]["versions"][0]]
    train_runs = done.results["scenarios"][SCENARIO]["data"]["splits"]["train"]["scenarios"]
    for method in ("uniform", "evoeye", "no-feedback"):
        row = rq2[method]
        assert row["campaigns"] == before[method]["campaigns"]  # no campaign ran again
        for campaign, versions, old in zip(row["campaigns"], row["versions"],
                                           before[method]["versions"], strict=True):
            assert not set(versions) & set(old)
            acquired = sum(len(r.scenario_ids) for r in read_rounds(done.root, campaign))
            for card, g0 in zip((load_version(done.root, v).card for v in versions), g0_seeds,
                                strict=True):
                assert card["parent"] is None  # from scratch, not from G_{R-1}
                assert card["hyperparameters"]["seed"] == g0["hyperparameters"]["seed"]
                assert card["data"]["train"]["runs"] == train_runs + acquired
                assert card["data"]["val"] == g0["data"]["val"]
    assert "final-retrain" in retrained.run.output and "nothing new" in retrained.again.output
    findings = (done.root.path / "reports" / "retrain" / "findings.md").read_text()
    assert "Generated by `evoeye results` from results.json." in findings  # no --docs: its own
    intro = (done.root.path / "reports" / "retrain" / "rq2.md").read_text()
    assert "trained from scratch on its D_R" in intro


def test_reproduce_regenerates_a_findings_file_from_the_runs_it_records(done, tmp_path) -> None:
    docs, readme = tmp_path / "docs", tmp_path / "README.md"
    docs.mkdir()
    (docs / "tiny.json").write_bytes(done.first_json)
    kept = {**done.results, "tables": [{**t, "scenario": "other"} for t in done.results["tables"]]}
    (docs / "kept.json").write_text(json.dumps(kept))  # another run's, with tables of its own
    made = RUNNER.invoke(app, ["findings", str(docs / "tiny.json"), str(docs / "kept.json"),
                               "--out", str(docs)])
    assert made.exit_code == 0, made.output
    (docs / "tiny.json").write_text("{}")  # stale: reproduce writes it again from the run
    kept_bytes = (docs / "kept.json").read_bytes()
    readme.write_text(f"# x\n{README_BEGIN}\nold text\n{README_END}\n")
    before = _state(done.root)
    run = RUNNER.invoke(app, ["reproduce", str(docs), "--root", f"tiny={done.root.path}",
                              "--only", "tiny", "--readme", str(readme)])
    assert run.exit_code == 0, run.output
    assert _state(done.root) == before  # every unit found done on the root that made it
    assert (docs / "tiny.json").read_bytes() == done.first_json
    assert (docs / "kept.json").read_bytes() == kept_bytes  # not re-run (--only), combined
    markdown = (docs / "tiny.md").read_text()
    assert markdown.startswith("# Monitoring effectiveness (RQ1) and the monitor ablation")
    assert "\n# Self-evolution (RQ2), the evolution ablation and AEM-Evo" in markdown
    combined = json.loads((docs / "findings.json").read_text())
    assert [s["path"] for s in combined["sources"]] == [str(docs / "tiny.json"),
                                                         str(docs / "kept.json")]
    assert combined["sources"][0]["config"] == done.results["config"]
    assert len(combined["tables"]) == 2 * len(done.results["tables"])
    assert "old text" not in readme.read_text()
    assert done.results["findings"][0]["claim"] in readme.read_text()
