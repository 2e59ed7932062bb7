"""The learning side of the rare-failure protocol: its config, its claim, and a small protocol
run end to end on real simulations (curves learned from, resumed, and refused when a recorded
run no longer reproduces)."""

from __future__ import annotations

import copy
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.results.findings import AGAINST, NOT_RUN, NOT_SHOWN, PARTLY, REPRODUCES
from evoeye.results.rare.config import UNWEIGHTED, LearnConfig, RareConfig
from evoeye.results.rare.findings import advice, learn_checks, rare_findings
from evoeye.results.rare.learn import curve_windows, learn_root, load_sets, no_skill
from evoeye.results.rare.part import rare_results
from evoeye.results.rare.report import advice_lines, rare_findings_markdown, rare_markdown
from evoeye.results.rare.runner import run_seed

# its module fixtures are built once only if its tests share a worker (pytest-xdist
# --dist loadgroup); spread over two, each worker builds them again
pytestmark = pytest.mark.xdist_group("rare-learn")

REGIME = "highway-cut-in:default"  # collisions are common: a small run learns something
LEARN = {"budgets": [5, 10], "test_runs": 12, "val_runs": 10, "val_collisions": 0,
         "controls": ["ce-is"]}  # ce-is's runs also unweighted: the control


def test_the_learning_config_is_validated_and_stored_whole():
    for bad in ({"budgets": [10]}, {"budgets": [20, 10]}, {"budgets": [0, 10]},
                {"members": 0}, {"members": 9}, {"recipe": "v9"}, {"test_runs": 0},
                {"val_collisions": -1}, {"horizon_s": 0.0}):
        with pytest.raises(ValueError):
            LearnConfig.from_dict(bad)
    with pytest.raises(ValueError, match="unknown learning config"):
        LearnConfig.from_dict({"budget": [5, 10]})
    with pytest.raises(ValueError, match="exceeds the runs"):
        RareConfig(runs=100, learn={"budgets": [50, 200]})
    assert "learn" not in RareConfig().to_dict()  # every recorded protocol's config as it was
    assert "controls" not in LearnConfig().to_dict()  # nor the learning side's keys
    for bad in ("uniform", "subset", "sobol"):  # no weights, or not among the strategies
        with pytest.raises(ValueError, match="learning controls"):
            RareConfig(strategies=("uniform", "ce-is", "subset"), learn={"controls": [bad]})
    with_control = RareConfig(learn={"controls": ["ce-is"]}).learning
    assert with_control.controls == ("ce-is",)
    assert with_control.curve_key() == LearnConfig().curve_key()  # learned curves resume
    with pytest.raises(ValueError, match="learning strategies"):
        RareConfig(learn={"strategies": ["subset"]})  # not among the protocol's strategies
    with pytest.raises(ValueError, match="learning controls"):  # its curves are not learned
        RareConfig(strategies=("uniform", "ce-is", "subset"),
                   learn={"strategies": ["subset"], "controls": ["ce-is"]})
    some = RareConfig(strategies=("uniform", "ce-is", "subset"),
                      learn={"strategies": ["ce-is"]}).learning
    assert [s for s in ("uniform", "ce-is", "subset") if some.learns(s)] == ["uniform", "ce-is"]
    assert LearnConfig().learns("subset")  # by default every strategy's curves
    assert some.curve_key() == LearnConfig().curve_key()
    cfg = RareConfig(learn={"members": 3})
    assert cfg.learn == {**LearnConfig().to_dict(), "members": 3}  # stored whole
    assert cfg.learning == LearnConfig(members=3)
    assert RareConfig.from_dict(cfg.to_dict()) == cfg
    assert cfg.changed()["learn"]["members"] == 3


def _cell(diff: float, low: float, high: float, p: float) -> dict:
    return {"n": 40, "mean_diff": diff, "ci_low": low, "ci_high": high, "p_value": p,
            "min_p": 1e-12}


def _summary(cell: dict, mde: float, failures: int) -> dict:
    vs = {"area": cell, "final": cell, "detectable": {"mde": mde}}
    return {"found": {}, "estimates": {}, "distinct": {},
            "learning": {"config": LearnConfig().to_dict(),
                         "sets": {"test": {"failures": failures}},
                         "strategies": {"uniform": {}, "ce-is": {"vs_reference": vs},
                                        "subset": {"vs_reference": vs}}}}


@pytest.mark.parametrize("cell, mde, failures, verdict, null", [
    (_cell(3.0, 1.0, 5.0, 0.001), 1.5, 60, REPRODUCES, False),
    (_cell(3.0, 1.0, 5.0, 0.001), 1.5, 49, NOT_SHOWN, False),  # too few Test failures
    (_cell(0.2, -0.8, 1.2, 0.6), 1.8, 60, NOT_SHOWN, True),  # the stated null
    (_cell(0.2, -2.8, 3.2, 0.6), 4.1, 60, NOT_SHOWN, False),  # a null too weak to state
    (_cell(-3.0, -5.0, -1.0, 0.001), 1.5, 60, AGAINST, False),
])
def test_a_learning_check_needs_a_gain_and_a_test_set_with_enough_failures(
        cell, mde, failures, verdict, null):
    (check,) = learn_checks({"r": _summary(cell, mde, failures)})  # subset's: unweighted
    assert check["strategy"] == "ce-is"
    assert (check["verdict"], check["null_at_mde"]) == (verdict, null)
    assert check["cell"] is cell and check["test_failures"] == failures


def test_the_learning_claim_holds_over_the_regimes_that_learned():
    win, null = _cell(3.0, 1.0, 5.0, 0.001), _cell(0.2, -0.8, 1.2, 0.6)
    claim = {f["id"]: f for f in rare_findings({"regimes": {
        "a": _summary(win, 1.5, 60), "b": _summary(win, 1.5, 60)}})}["rare-learn"]
    assert claim["verdict"] == REPRODUCES
    claim = {f["id"]: f for f in rare_findings({"regimes": {
        "a": _summary(win, 1.5, 60), "b": _summary(null, 1.8, 60)}})}["rare-learn"]
    assert claim["verdict"] == PARTLY
    plain = {"found": {}, "estimates": {}, "distinct": {}}
    claim = {f["id"]: f for f in rare_findings({"regimes": {"a": plain}})}["rare-learn"]
    assert claim["verdict"] == NOT_RUN


def test_advice_names_the_runs_to_learn_from_only_where_learning_was_shown():
    found = {"regime": "r", "strategy": "ce-is", "ratio": 2.0, "ratio_low": 1.5,
             "ratio_high": 3.0, "verdict": NOT_SHOWN}
    learned = [{"id": "rare-found", "checks": [found, {**found, "regime": "s"}]},
               {"id": "rare-learn", "checks": learn_checks({
                   "r": _summary(_cell(3.0, 1.0, 5.0, 0.001), 1.5, 60),
                   "s": _summary(_cell(0.2, -0.8, 1.2, 0.6), 1.8, 60)})}]
    rows = advice(learned)
    assert rows["r"] == {"find": "ce-is", "estimate": "uniform", "learn": "ce-is"}
    assert rows["s"]["learn"] == "uniform"  # a null: no reason to leave p
    assert "learn" not in advice([learned[0]])["r"]  # not run: no advice either way
    text = "\n".join(advice_lines(learned))
    assert "to train a monitor on, the runs of **ce-is** weighted by their p/q" in text
    assert "to train a monitor on, the runs of **uniform**." in text


@pytest.fixture(scope="module")
def learned(tmp_path_factory) -> tuple[DataRoot, RareConfig, dict]:
    root = DataRoot(tmp_path_factory.mktemp("rare-learn"))
    config = RareConfig(regimes=(REGIME,), strategies=("uniform", "ce-is"), seeds=(0, 1),
                        runs=10, batch=5, explain=False, learn=LEARN)
    out, _ = rare_results(root, config, workers=2)
    return root, config, out


def test_every_curve_is_learned_from_at_every_budget_and_judged_on_its_test_set(learned):
    root, config, out = learned
    assert out["failed"] == []
    learning = out["regimes"][REGIME]["learning"]
    test = learning["sets"]["test"]
    assert test["runs"] == 12 and learning["sets"]["val"]["runs"] == 10
    assert learning["budgets"] == [5, 10]
    assert set(learning["strategies"]) == {"uniform", "ce-is", "ce-is" + UNWEIGHTED}
    sets, weight = load_sets(learn_root(root, REGIME), config.learning, config.data_seed)
    assert weight is None  # no further Test runs were drawn: every window counts once
    share = sets["test"].label.mean()
    assert test["unsafe"] == int(sets["test"].label.sum())
    # a no-skill monitor scores every frame alike: its AUPRC is the Test Set's unsafe share
    flat = no_skill(SimpleNamespace(val=sets["val"], judging={"test": sets["test"]},
                                    judging_weights={}))
    assert flat["test"]["auprc"] == pytest.approx(share)
    for name, row in learning["strategies"].items():
        assert row["seeds"] == 2 and len(row["auprc"]) == 2
        curves = out["regimes"][REGIME]["found"][name.removesuffix(UNWEIGHTED)]
        assert curves["collisions"] >= row["collisions"][-1]  # trained on the runs it found
    for name in ("uniform", "ce-is"):
        assert ("vs_reference" in learning["strategies"][name]) == (name == "ce-is")
    control = learning["strategies"]["ce-is" + UNWEIGHTED]
    assert control["effective_runs"] == [5.0, 10.0]  # every run weighs 1
    assert control["collisions"] == learning["strategies"]["ce-is"]["collisions"]  # same runs
    assert "weights_add" in control and "weights_add" not in learning["strategies"]["ce-is"]
    text = rare_markdown(out)
    assert "### What a monitor learns from these runs" in text
    assert "**What the weights add**, ce-is's runs weighted − unweighted" in text
    assert "fewer than the 50 a check needs" in text  # 12 Test runs cannot hold 50 failures
    claim = {f["id"]: f for f in out["findings"]}["rare-learn"]
    assert [c["verdict"] for c in claim["checks"]] == [NOT_SHOWN]
    assert "area − Uniform's" in rare_findings_markdown(out["findings"])


def test_a_rerun_learns_nothing_again_and_gives_the_same_figures(learned):
    root, config, out = learned
    again, computed = rare_results(root, config, workers=1)
    assert computed == 0
    assert again["regimes"] == out["regimes"]


def test_learning_limited_to_some_strategies_reuses_their_learned_curves(learned):
    root, config, out = learned
    only = replace(config, learn={**LEARN, "controls": [], "strategies": ["uniform"]})
    again, computed = rare_results(root, only, workers=1)
    assert computed == 0  # every curve and every learned curve was found in the ledger
    regime = again["regimes"][REGIME]
    assert set(regime["found"]) == {"uniform", "ce-is"}  # the testing side keeps every one
    assert set(regime["learning"]["strategies"]) == {"uniform"}
    assert regime["learning"]["strategies"]["uniform"] == (
        out["regimes"][REGIME]["learning"]["strategies"]["uniform"])


def test_a_run_that_no_longer_reproduces_its_record_is_an_error(learned):
    root, config, _ = learned
    from evoeye import __version__
    from evoeye.results.ledger import Ledger

    key = {**config.unit(REGIME, "uniform", 0), "software_version": __version__}
    curve = Ledger(root).remember("rare-curve", key, lambda: pytest.fail("not recorded"))
    windows, ids = curve_windows(REGIME, curve, lambda k: run_seed(config, REGIME, "uniform",
                                                                   0, k), 3, config.learning)
    assert len(windows) == len(ids) == 3 and len(set(ids)) == 3
    tampered = copy.deepcopy(curve)
    tampered["runs"][1]["collided"] = not tampered["runs"][1]["collided"]
    with pytest.raises(RuntimeError, match="did not reproduce its recorded outcome"):
        curve_windows(REGIME, tampered, lambda k: run_seed(config, REGIME, "uniform", 0, k), 3,
                      config.learning)
    assert np.isfinite(windows[0].label).all()
