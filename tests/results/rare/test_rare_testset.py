"""A Test Set for rare failures: the Test stream drawn on to its failures (outcome first, only
the collisions logged), resumed from its record, and weighted back to the whole stream."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from sklearn.metrics import average_precision_score

from evoeye.batch import plan_uniform, run_batch
from evoeye.monitor.calibration import calibrate
from evoeye.paths import DataRoot
from evoeye.results.efficiency.learner import Learner
from evoeye.results.rare.config import LearnConfig
from evoeye.results.rare.learn import load_sets, no_skill, prepare_sets, set_batch
from evoeye.results.rare.report import describe_test_set
from evoeye.results.rare.testset import TEST_DRAW_FILE, draw_test_failures, more_batch
from evoeye.sim.episode import STATUS_OK
from evoeye.sim.runner import run_episode

# its module fixtures are built once only if its tests share a worker (pytest-xdist
# --dist loadgroup); spread over two, each worker builds them again
pytestmark = pytest.mark.xdist_group("rare-testset")

REGIME, SCENARIO = "highway-cut-in:default", "highway-cut-in"  # collisions are common here
DATA_SEED = 500
LEARN = LearnConfig(budgets=(5, 10), test_runs=8, val_runs=4, val_collisions=0,
                    min_test_failures=4, test_max_runs=200)


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    root = DataRoot(tmp_path_factory.mktemp("rare-testset"))
    data, draw = prepare_sets(root, REGIME, LEARN, DATA_SEED)
    return data, draw


def test_the_stream_is_drawn_on_until_it_holds_its_failures_and_only_they_are_logged(drawn):
    data, draw = drawn
    batch, seed = set_batch("test", DATA_SEED)
    specs = plan_uniform(SCENARIO, draw.runs, seed, batch=batch)  # the stream, simulated whole
    outcomes = [run_episode(s).outcome for s in specs]
    ok = np.array([o.status == STATUS_OK for o in outcomes])
    hit = ok & np.array([bool(o.collided) for o in outcomes])
    n, chunk = LEARN.test_runs, LEARN.test_runs  # chunks of test_runs runs when that is fewer
    assert draw.collisions == hit.sum() >= LEARN.min_test_failures
    assert hit[: draw.runs - chunk].sum() < LEARN.min_test_failures  # cut at the first chunk
    assert draw.further == tuple(s.scenario_id for s, h in zip(specs[n:], hit[n:], strict=True)
                                 if h)
    logged = data.batch_dir(SCENARIO, more_batch(seed)).glob("*.mcap")
    assert sorted(p.name.removesuffix(".mcap") for p in logged) == sorted(draw.further)
    stream_safe, batch_safe = (ok & ~hit).sum(), (ok[:n] & ~hit[:n]).sum()
    assert draw.safe_weight == pytest.approx(stream_safe / batch_safe) and draw.safe_weight > 1


def test_a_re_run_simulates_nothing_more_and_a_cap_cuts_the_stream(drawn):
    data, draw = drawn
    batch, seed = set_batch("test", DATA_SEED)
    record = (data.path / TEST_DRAW_FILE).read_bytes()
    base = run_batch(plan_uniform(SCENARIO, LEARN.test_runs, seed, batch=batch), data)
    assert base.skipped == LEARN.test_runs  # simulated by prepare_sets
    again = draw_test_failures(data, REGIME, seed, base, LEARN.min_test_failures,
                               LEARN.test_max_runs)
    assert again == draw and (data.path / TEST_DRAW_FILE).read_bytes() == record
    capped = draw_test_failures(data, REGIME, seed, base, 10_000, 2 * LEARN.test_runs)
    assert capped.runs == 2 * LEARN.test_runs  # one further chunk, whatever it held
    assert set(capped.further) <= set(draw.further)
    assert (data.path / TEST_DRAW_FILE).read_bytes() == record  # it was drawn already


def test_the_test_set_holds_every_failure_and_weighs_its_safe_runs_back(drawn):
    data, draw = drawn
    sets, weight = load_sets(data, LEARN, DATA_SEED, draw)
    test = sets["test"]
    ids = np.asarray(test.scenario_id).astype(str)
    assert set(draw.further) <= set(ids)  # the further failures are in
    hit_runs = set(np.unique(ids[test.label == 1]))
    assert len(hit_runs) <= draw.collisions
    heavy = weight > 1
    assert np.allclose(weight[heavy], draw.safe_weight) and not (heavy & (test.label == 1)).any()
    assert not np.isin(ids[heavy], list(hit_runs | set(draw.further))).any()
    # the no-skill figure of a weighted set is its weighted unsafe share
    flat = no_skill(SimpleNamespace(val=sets["val"], judging={"test": test},
                                    judging_weights={"test": weight}))
    share = float((weight * test.label).sum() / weight.sum())
    assert flat["test"]["auprc"] == pytest.approx(share)
    assert share < test.label.mean()  # weighted back towards the stream's rarer failures


def test_the_further_test_runs_are_a_later_field_of_the_learning_config():
    assert "test_max_runs" not in LearnConfig().to_dict()  # recorded configs keep their keys
    assert LearnConfig(test_max_runs=30_000).to_dict()["test_max_runs"] == 30_000
    with pytest.raises(ValueError, match="must exceed test_runs"):
        LearnConfig(test_runs=4000, test_max_runs=4000)


def test_a_monitor_is_judged_on_the_weighted_test_set_as_the_stream_would_judge_it(drawn):
    data, draw = drawn
    sets, weight = load_sets(data, LEARN, DATA_SEED, draw)
    test = sets["test"]
    rng = np.random.default_rng(0)
    scores = np.clip(0.3 * test.label + rng.uniform(0, 1, len(test)), 0, 1)  # some skill
    thresholds = calibrate(rng.uniform(0, 1, len(sets["val"])), sets["val"].label)
    monitor = SimpleNamespace(score=lambda w: scores, thresholds=thresholds)
    learner = Learner(sets["val"], {"test": test}, judging_weights={"test": weight})
    judged = learner.judge(monitor)["test"]
    assert judged["auprc"] == pytest.approx(average_precision_score(test.label, scores,
                                                                    sample_weight=weight))
    plain = Learner(sets["val"], {"test": test}).judge(monitor)["test"]
    assert judged["auprc"] < plain["auprc"]  # the stream's rarer failures are harder to rank
    assert "stratified by outcome" in describe_test_set({"runs": 1, "failures": 1, "unsafe": 1,
                                                     "windows": 2, **draw.to_dict()})
