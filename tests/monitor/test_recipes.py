"""Training recipes: v1 keeps its card and ids, names are checked, batches and schedules."""

from __future__ import annotations

import math
from dataclasses import asdict, fields, replace

import numpy as np
import pytest
import torch

from evoeye.monitor import batching, recipes
from evoeye.monitor.recipes import (
    ADDED_FIELDS,
    RECIPES,
    TrainParams,
    card_hyperparameters,
    recipe_params,
)

V1_CARD_KEYS = {"seed", "epochs", "patience", "batch_size", "lr", "weight_decay", "grad_clip",
                "pos_weight", "threads"}  # what a card recorded before recipes had names


def test_a_v1_card_records_what_it_did_before_recipes_had_names() -> None:
    assert set(card_hyperparameters(recipe_params("v1", seed=3))) == V1_CARD_KEYS
    v1 = card_hyperparameters(TrainParams(seed=3, epochs=2))
    assert v1 == {k: v for k, v in asdict(TrainParams(seed=3, epochs=2)).items()
                  if k in V1_CARD_KEYS}
    # every other recipe says which it is, and how it differs from v1
    v2 = card_hyperparameters(RECIPES["v2"])
    assert v2["recipe"] == "v2" and v2["batching"] == "chunks"
    assert set(ADDED_FIELDS) == {f.name for f in fields(TrainParams)} - V1_CARD_KEYS


def test_the_default_recipe_is_v3_and_overrides_apply_on_top() -> None:
    params = recipe_params(epochs=3, lr=0.5)
    assert params.recipe == recipes.DEFAULT_RECIPE == "v3"
    assert (params.epochs, params.lr, params.batch_size) == (3, 0.5, RECIPES["v2"].batch_size)
    assert recipe_params("v1") == TrainParams() == RECIPES[recipes.LEGACY_RECIPE]
    # v3 trains the FusionMonitor as v2 does: only its name, and the AEM's part, differ
    assert replace(RECIPES["v3"], recipe="v2") == RECIPES["v2"]


def test_the_command_trains_the_trigger_recipe_and_the_studies_keep_v3() -> None:
    # `evoeye train` trains lookahead-v1 (its network: RECIPE_NETWORKS); train_monitor, RQ1,
    # campaigns and the studies keep v3, what their recorded figures were made with
    assert (recipes.COMMAND_RECIPE, recipes.DEFAULT_RECIPE) == ("lookahead-v1", "v3")
    assert recipes.RECIPE_NETWORKS[recipes.COMMAND_RECIPE] == {"context_len": 20,
                                                               "kinematics": True}
    assert RECIPES["lookahead-v1"].target == "critical"


@pytest.mark.parametrize(("recipe", "overrides", "message"), [
    ("v9", {}, r"unknown training recipe 'v9'; known: \['lookahead-v1', 'v1', 'v2', 'v3'\]"),
    ("v2", {"learning_rate": 1.0}, r"unknown training parameter\(s\) \['learning_rate'\]"),
    ("v2", {"batching": "runs"}, "unknown batching 'runs'"),
    ("v2", {"schedule": "step"}, "unknown schedule 'step'"),
    ("v2", {"chunk_windows": 0}, "chunk_windows must be >= 1"),
])
def test_bad_recipes_and_parameters_are_refused_by_name(recipe: str, overrides: dict,
                                                         message: str) -> None:
    with pytest.raises(ValueError, match=message):
        recipe_params(recipe, **overrides)


def test_the_names_are_the_registries() -> None:
    assert tuple(batching.BATCHINGS) == recipes.BATCHINGS
    assert tuple(batching.SCHEDULES) == recipes.SCHEDULES


@pytest.mark.parametrize(("n", "chunk"), [(0, 4), (1, 4), (10, 1), (103, 8), (64, 64)])
def test_a_chunk_order_is_a_permutation_of_runs_of_consecutive_windows(n: int,
                                                                        chunk: int) -> None:
    gen = torch.Generator().manual_seed(n)
    order = batching.chunk_order(n, chunk, gen)
    assert sorted(order.tolist()) == list(range(n))
    # it steps by one but where one chunk ends and another begins: at most once per chunk
    assert np.count_nonzero(np.diff(order) != 1) <= n // chunk + 1
    again = batching.chunk_order(n, chunk, torch.Generator().manual_seed(n))
    assert np.array_equal(order, again)  # the generator decides everything


def test_chunk_orders_differ_between_epochs() -> None:
    gen = torch.Generator().manual_seed(0)
    first, second = batching.chunk_order(500, 16, gen), batching.chunk_order(500, 16, gen)
    assert not np.array_equal(first, second)


def test_the_learning_rate_warms_up_then_follows_the_schedule() -> None:
    params = TrainParams(lr=0.1, epochs=4, schedule="cosine", warmup_epochs=1.0)
    lr_at = batching.lr_schedule(params, steps_per_epoch=10)
    assert [lr_at(s) for s in (0, 4, 9)] == pytest.approx([0.01, 0.05, 0.1])
    assert lr_at(10) == pytest.approx(0.1)  # the decay starts at the peak …
    assert lr_at(25) == pytest.approx(0.05)  # … is half way after half its 30 steps …
    assert lr_at(39) == pytest.approx(0.1 * 0.5 * (1 + math.cos(math.pi * 29 / 30)))
    assert lr_at(40) == lr_at(99) == 0.0  # … and stays at 0 past the planned epochs
    constant = batching.lr_schedule(TrainParams(lr=0.3), steps_per_epoch=10)
    assert {constant(s) for s in range(100)} == {0.3}  # v1: its one learning rate, exactly


def test_hold_decay_holds_the_peak_then_falls_linearly_to_zero() -> None:
    params = TrainParams(lr=0.2, epochs=10, schedule="hold-decay")
    lr_at = batching.lr_schedule(params, steps_per_epoch=10)  # 100 steps, the last 30 decay
    assert {lr_at(s) for s in range(71)} == {0.2}
    assert lr_at(85) == pytest.approx(0.2 * 15 / 30) and lr_at(100) == 0.0
    assert all(lr_at(s) >= lr_at(s + 1) for s in range(100))
