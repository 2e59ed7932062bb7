"""Monitor-oriented feedback f_r(x) = mean |ŷ − y| per scenario, and its normalisation f̄."""

import numpy as np
import pytest

from evoeye.evolve.search import normalise_feedback, scenario_feedback


def test_feedback_on_a_hand_built_example():
    scores = np.array([0.9, 0.2, 0.4, 0.0, 1.0])
    labels = np.array([1, 0, 1, 0, 0])
    ids = np.array(["b", "a", "b", "c", "a"])
    fb = scenario_feedback(scores, labels, ids)
    # a: |0.2-0| and |1.0-0| -> 0.6; b: |0.9-1| and |0.4-1| -> 0.35; c: |0-0| -> 0
    assert list(fb.scenario_id) == ["a", "b", "c"]
    np.testing.assert_allclose(fb.feedback, [0.6, 0.35, 0.0])
    np.testing.assert_array_equal(fb.n_contexts, [2, 2, 1])
    assert fb.as_dict() == pytest.approx({"a": 0.6, "b": 0.35, "c": 0.0})


def test_aligned_follows_the_records_order_and_marks_unscored_runs():
    fb = scenario_feedback(np.array([0.25, 1.0]), np.array([0, 0]), np.array(["s2", "s9"]))
    out = fb.aligned(np.array(["s9", "s0", "s2", "zz"]))
    np.testing.assert_allclose(out, [1.0, np.nan, 0.25, np.nan])


def test_vectorised_feedback_matches_a_plain_loop():
    rng = np.random.default_rng(1)
    ids = rng.integers(0, 40, size=3000)
    scores, labels = rng.uniform(size=3000), rng.integers(0, 2, size=3000)
    fb = scenario_feedback(scores, labels, ids)
    for sid, f in zip(fb.scenario_id, fb.feedback, strict=True):
        mine = ids == sid
        assert f == pytest.approx(np.mean(np.abs(scores[mine] - labels[mine])))


@pytest.mark.parametrize(
    ("scores", "labels", "ids", "match"),
    [
        ([0.1, 0.2], [0, 1], ["a"], "length mismatch"),
        ([0.1, np.nan], [0, 1], ["a", "a"], "finite"),
        ([0.1, 0.2], [0, 2], ["a", "a"], "0 or 1"),
    ],
)
def test_bad_inputs_are_refused(scores, labels, ids, match):
    with pytest.raises(ValueError, match=match):
        scenario_feedback(np.array(scores), np.array(labels), np.array(ids))


def test_normalised_feedback_spans_zero_to_one_and_keeps_unscored_runs_unscored():
    f = np.array([0.2, np.nan, 0.6, 0.4, 0.2])
    fbar = normalise_feedback(f)
    np.testing.assert_allclose(fbar, [0.0, np.nan, 1.0, 0.5, 0.0])
    rng = np.random.default_rng(0)
    g = normalise_feedback(rng.uniform(0.1, 0.3, size=500))
    assert g.min() == 0.0 and g.max() == 1.0


def test_equal_feedback_normalises_to_zero_instead_of_dividing_by_zero():
    np.testing.assert_array_equal(normalise_feedback(np.full(4, 0.3)), np.zeros(4))
    assert np.isnan(normalise_feedback(np.array([np.nan, np.nan]))).all()


def test_prior_corrected_undoes_the_weighted_bce_odds_shift() -> None:
    from evoeye.evolve.search.feedback import prior_corrected

    p = np.array([0.01, 0.2, 0.5, 0.9])  # true probabilities
    w = 24.0
    weighted_optimum = w * p / (w * p + 1 - p)  # argmin of the pos_weight-w BCE at rate p
    assert np.allclose(prior_corrected(weighted_optimum, w), p)
    assert np.allclose(prior_corrected(p, 1.0), p)  # no weight, nothing to undo
    assert np.all(np.diff(prior_corrected(np.linspace(0, 1, 11), w)) >= 0)  # monotone
    with pytest.raises(ValueError, match="pos_weight"):
        prior_corrected(p, 0.0)
