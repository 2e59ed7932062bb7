"""Importance-weighted training: a run's weight acts as that many copies of it, and off (or
with every weight 1) nothing changes."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from evoeye.monitor.importance import window_weights
from evoeye.monitor.recipes import RECIPES, card_hyperparameters, recipe_key, recipe_params
from evoeye.monitor.train import fit_windows
from evoeye.store import RunFilter, load_windows

FULL_BATCH = {"epochs": 3, "patience": 3, "batch_size": 100_000, "lr": 3e-3}


@pytest.fixture(scope="module")
def sets(tiny):
    def windows(split):
        return load_windows(tiny.root, RunFilter(logical_scenario=tiny.scenario, split=split),
                            horizon_s=tiny.horizon_s)

    return windows("train"), windows("val")


def state(trained):
    return {k: v.clone() for k, v in trained.result.net.state_dict().items()}


def test_weights_are_self_normalised_clipped_and_one_where_unknown():
    ids = np.array(["a"] * 2 + ["b"] * 4 + ["c"] * 4 + ["d"] * 2)
    w, summary = window_weights(ids, {"a": 2.0, "b": 1.0, "c": 1.0})  # d: no q, weight 1
    assert w.mean() == pytest.approx(1.0)
    assert w[0] / w[2] == pytest.approx(2.0) and w[-1] == pytest.approx(w[2])
    assert summary["weighted_runs"] == 3 and summary["clipped_runs"] == 0
    w, summary = window_weights(np.array(list("abcd")), {"a": 1000.0})
    assert summary["clipped_runs"] == 1  # 1000 / mean → capped at √4 = 2
    assert w[0] / w[1] == pytest.approx(2.0 / (4.0 / 1003.0))
    with pytest.raises(ValueError, match="run b: its weight p/q must be finite and > 0"):
        window_weights(np.array(list("ab")), {"b": 0.0})


def test_a_doubled_weight_trains_as_two_copies_of_the_run(tiny, sets) -> None:
    """Full-batch training: the weighted loss Σ w·ℓ / B, with a run at twice the others'
    weight (windows' mean weight 1), is the loss of the set holding that run twice, and so is
    the weighted pos_weight: the same gradients, the same network."""
    train, val = sets
    first = train.scenario_id[0]
    mine = np.flatnonzero(train.scenario_id == first)
    doubled = train.subset(np.r_[np.arange(len(train)), mine])
    params = recipe_params("v1", seed=3, **FULL_BATCH)
    copies = fit_windows(doubled, val, params)
    weighted = fit_windows(train, val, recipe_params("v1", seed=3, importance_weights=True,
                                                     **FULL_BATCH), run_weights={first: 2.0})
    plain = fit_windows(train, val, params)
    assert weighted.result.pos_weight == pytest.approx(copies.result.pos_weight, rel=1e-6)
    assert weighted.result.importance["weighted_runs"] == 1
    a, b, c = state(weighted), state(copies), state(plain)
    for key in a:
        torch.testing.assert_close(a[key], b[key], rtol=1e-4, atol=1e-5)
    assert any(not torch.allclose(a[k], c[k], rtol=1e-4, atol=1e-5) for k in a)


def test_every_weight_one_is_the_unweighted_training(tiny, sets) -> None:
    """Runs without a recorded q weigh 1: the same network as off, to rounding (off runs the
    earlier code path itself, and its networks are those it gave, bit for bit)."""
    train, val = sets
    off = fit_windows(train, val, recipe_params("v1", seed=5, **FULL_BATCH))
    ones = fit_windows(train, val, recipe_params("v1", seed=5, importance_weights=True,
                                                 **FULL_BATCH))
    a, b = state(off), state(ones)
    for key in a:
        torch.testing.assert_close(a[key], b[key], rtol=1e-5, atol=1e-6)
    assert off.result.importance is None and ones.result.importance["effective_runs"] == 6
    with pytest.raises(ValueError, match="importance_weights is off"):
        fit_windows(train, val, recipe_params("v1", seed=5, **FULL_BATCH),
                    run_weights={"x": 2.0})


def test_the_option_leaves_earlier_cards_and_ledger_keys_alone() -> None:
    for name in ("v1", "v2", "v3"):
        assert "importance_weights" not in card_hyperparameters(RECIPES[name])
        assert "importance_weights" not in recipe_key(RECIPES[name])
    on = recipe_params("v3", importance_weights=True)
    assert card_hyperparameters(on)["importance_weights"] is True
    assert recipe_key(on)["importance_weights"] is True
