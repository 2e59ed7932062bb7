"""Training aimed at warning in time (evoeye.monitor.lookahead): which windows train, which
epoch is kept — on the tiny warehouse (colliding runs collide at frame 30, H = 1 s)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from sklearn.metrics import average_precision_score, roc_auc_score

from evoeye.monitor.lookahead import (
    EGO_ACCEL,
    PAUC_MAX_FPR,
    collision_lead_s,
    near_miss_windows,
    preventable_windows,
    selection_metric,
    training_windows,
)
from evoeye.monitor.recipes import RECIPES, card_hyperparameters, recipe_params
from evoeye.monitor.train import fit_windows
from evoeye.store import RunFilter, load_windows

COLLISION_FRAME, RATE_HZ = 30, 20.0  # the tiny warehouse's (tests/monitor/conftest.py)


@pytest.fixture(scope="module")
def train(tiny):
    return load_windows(tiny.root, RunFilter(logical_scenario=tiny.scenario, split="train"),
                        horizon_s=tiny.horizon_s)


def colliding(windows) -> np.ndarray:
    """(B,) bool: the window's run collides."""
    runs = {s for s, y in zip(windows.scenario_id, windows.label, strict=True) if y}
    return np.array([s in runs for s in windows.scenario_id])


def test_the_lead_to_the_collision_is_read_from_the_windows_alone(train) -> None:
    lead = collision_lead_s(train)
    hit = colliding(train)
    assert hit.any() and (~hit).any()
    np.testing.assert_allclose(lead[hit], (COLLISION_FRAME - train.frame[hit]) / RATE_HZ,
                               atol=1e-9)
    assert np.isinf(lead[~hit]).all()


def test_preventable_windows_leave_out_only_the_last_unsafe_moments(train) -> None:
    assert preventable_windows(train, 0.0) is train
    kept = preventable_windows(train, 0.5)
    n_colliding = len({s for s, y in zip(train.scenario_id, train.label, strict=True) if y})
    # frames 21 … 29 lie less than 0.5 s before the collision at frame 30; frame 20 is kept
    assert len(train) - len(kept) == 9 * n_colliding
    late = (kept.label == 1) & (kept.frame > COLLISION_FRAME - 10)
    assert not late.any() and ((kept.label == 1) & (kept.frame == 20)).sum() == n_colliding


def braking(train, run_of, frame: int):
    """`train` with no hard braking anywhere but at `frame` of the run `run_of` picks."""
    control = train.features.control.copy()
    control[:, EGO_ACCEL] = 0.0
    sid = next(s for s in dict.fromkeys(train.scenario_id) if run_of(train, s))
    row = train.context[(train.scenario_id == sid) & (train.frame == frame), -1]
    control[row, EGO_ACCEL] = -5.0
    return replace(train, features=replace(train.features, control=control)), sid


def test_a_near_miss_is_a_safe_window_with_hard_braking_within_h(train) -> None:
    safe_run = lambda w, s: not w.label[w.scenario_id == s].any()  # noqa: E731
    windows, sid = braking(train, safe_run, 25)
    near = near_miss_windows(windows)
    # frames 5 … 25 have frame 25 within H = 1 s (20 frames) ahead, itself included
    assert sorted(windows.frame[near]) == list(range(5, 26))
    assert set(windows.scenario_id[near]) == {sid}
    # in a colliding run the unsafe windows stay unsafe: only its safe ones become near misses
    hit_run = lambda w, s: w.label[w.scenario_id == s].any()  # noqa: E731
    windows, _ = braking(train, hit_run, 15)
    assert sorted(windows.frame[near_miss_windows(windows)]) == list(range(0, 10))


def test_near_misses_train_safe_ignored_or_unsafe(train) -> None:
    windows, _ = braking(train, lambda w, s: not w.label[w.scenario_id == s].any(), 25)
    near = near_miss_windows(windows)
    assert near.sum() == 21
    assert training_windows(windows, 0.0, "safe") is windows
    ignored = training_windows(windows, 0.0, "ignored")
    assert len(ignored) == len(windows) - 21 and ignored.label.sum() == windows.label.sum()
    unsafe = training_windows(windows, 0.0, "unsafe")
    assert len(unsafe) == len(windows) and unsafe.label.sum() == windows.label.sum() + 21
    with pytest.raises(ValueError, match="unknown near_misses 'maybe'"):
        training_windows(windows, 0.0, "maybe")


def test_selection_metrics_are_sklearns() -> None:
    rng = np.random.default_rng(0)
    y = (rng.random(5000) < 0.1).astype(int)
    s = rng.random(5000) + y * 0.3
    assert selection_metric("auprc", s, y) == pytest.approx(average_precision_score(y, s))
    assert selection_metric("pauc", s, y) == pytest.approx(
        roc_auc_score(y, s, max_fpr=PAUC_MAX_FPR))
    assert selection_metric("pauc", s, np.zeros(5000)) is None
    with pytest.raises(ValueError, match="unknown selection"):
        selection_metric("f1", s, y)


def test_fit_selects_on_pauc_and_trains_on_the_preventable_windows(tiny, train) -> None:
    val = load_windows(tiny.root, RunFilter(logical_scenario=tiny.scenario, split="val"),
                       horizon_s=tiny.horizon_s)
    params = recipe_params("v1", **{**tiny.fast, "epochs": 4, "patience": 4},
                           select_on="pauc", min_lead_s=0.5)
    trained = fit_windows(train, val, params)
    history = trained.result.history
    assert all("pauc" in row for row in history)
    best = max(range(len(history)), key=lambda i: history[i]["pauc"] - 1e-6 * i)
    assert trained.result.best_epoch == history[best]["epoch"]
    kept = preventable_windows(train, 0.5)
    n_pos = int(kept.label.sum())
    assert trained.result.pos_weight == pytest.approx((len(kept) - n_pos) / n_pos)


def test_the_options_are_checked_and_earlier_recipes_keep_their_cards() -> None:
    for bad, message in (({"select_on": "f1"}, "unknown selection"),
                         ({"near_misses": "maybe"}, "unknown near_misses"),
                         ({"min_lead_s": -1.0}, "min_lead_s must be >= 0")):
        with pytest.raises(ValueError, match=message):
            recipe_params("v3", **bad)
    for name in ("v1", "v2", "v3"):
        assert not {"select_on", "min_lead_s", "near_misses"} & set(
            card_hyperparameters(RECIPES[name]))
    card = card_hyperparameters(recipe_params("v3", select_on="pauc", min_lead_s=0.5))
    assert (card["select_on"], card["min_lead_s"]) == ("pauc", 0.5)


def test_ledger_keys_of_earlier_recipes_do_not_change() -> None:
    from dataclasses import asdict

    from evoeye.monitor.recipes import LATER_FIELDS, recipe_key
    from evoeye.results.efficiency.learner import Learner

    for name in ("v1", "v2", "v3"):
        params = recipe_params(name, seed=7)
        before = {k: v for k, v in asdict(params).items()  # what the keys held before
                  if k != "seed" and k not in LATER_FIELDS}
        assert recipe_key(params) == before
        assert Learner(None, {}, params).recipe == before  # type: ignore[arg-type]
    assert recipe_key(recipe_params("v3", min_lead_s=0.5))["min_lead_s"] == 0.5
