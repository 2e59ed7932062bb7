"""Several seeds at once: the versions each seed gives alone, bit for bit; recipes on the card."""

from __future__ import annotations

import pytest
import torch

from evoeye.monitor.registry import read_card
from evoeye.monitor.train import train_monitor, train_monitors


def test_seeds_trained_together_are_the_seeds_trained_alone(tiny) -> None:
    kwargs = {"horizon_s": tiny.horizon_s, **tiny.fast, "epochs": 3}
    alone = [train_monitor(tiny.root, tiny.scenario, seed=s, **kwargs) for s in (5, 6, 7)]
    rows: list[dict] = []
    together = train_monitors(tiny.root, tiny.scenario, seeds=[7, 5, 6], parallel=2,
                              progress=rows.append, **kwargs)
    # a version id is a hash of the weights: the same ids are the same weights
    assert together == [alone[2], alone[0], alone[1]] and len(set(alone)) == 3
    assert sorted({row["seed"] for row in rows}) == [5, 6, 7]
    assert sum(row["seed"] == 5 for row in rows) == read_card(tiny.root, alone[0])[
        "training"]["epochs_run"]


def test_seeds_with_dropout_train_one_after_the_other_and_still_match(tiny) -> None:
    kwargs = {"horizon_s": tiny.horizon_s, **tiny.fast, "epochs": 2, "dropout": 0.2}
    alone = [train_monitor(tiny.root, tiny.scenario, seed=s, **kwargs) for s in (1, 2)]
    assert train_monitors(tiny.root, tiny.scenario, seeds=[1, 2], **kwargs) == alone


def test_repeated_or_no_seeds_are_refused(tiny) -> None:
    for seeds in ([], [1, 1]):
        with pytest.raises(ValueError, match="distinct training seeds"):
            train_monitors(tiny.root, tiny.scenario, seeds=seeds, horizon_s=tiny.horizon_s)


@pytest.mark.parametrize("recipe", ["v1", "v2"])
def test_the_card_names_the_recipe_and_records_cpu_time_and_device(tiny, recipe: str) -> None:
    version = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, recipe=recipe,
                            epochs=2, device="cpu")
    card = read_card(tiny.root, version)
    assert card["recipe"] == recipe and card["training"]["device"] == "cpu"
    assert card["training"]["cpu_s"] > 0 and card["training"]["epochs_run"] <= 2
    hp = card["hyperparameters"]
    assert ("batching" in hp) is (recipe != "v1")  # v1's card as before recipes had names
    assert train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, recipe=recipe,
                         epochs=2, device="cpu") == version


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA device")
def test_a_gpu_trains_and_scores_a_monitor_that_beats_chance(tiny) -> None:
    version = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=0,
                            device="cuda", **tiny.fast)
    card = read_card(tiny.root, version)
    assert card["training"]["device"].startswith("cuda")
    assert card["metrics"]["val"]["auroc"] > 0.9
