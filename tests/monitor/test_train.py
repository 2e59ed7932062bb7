"""Training: it learns, it is repeatable, its card says what it did, fine-tuning keeps lineage."""

from __future__ import annotations

import pytest
import torch

from evoeye.monitor.card import ranking_metrics
from evoeye.monitor.registry import load_monitor, read_card
from evoeye.monitor.train import train_monitor
from evoeye.store import RunFilter, load_windows


def test_trained_monitor_clearly_beats_chance(tiny, trained: str) -> None:
    card = read_card(tiny.root, trained)
    assert card["metrics"]["val"]["auroc"] > 0.9
    monitor = load_monitor(tiny.root, trained)
    test = load_windows(tiny.root, tiny.ids["test"], context_len=5, horizon_s=tiny.horizon_s)
    scores = monitor.score(test)
    assert ranking_metrics(scores, test.label)["auroc"] > 0.9


def test_same_seed_gives_same_weights_and_version(tiny, trained: str) -> None:
    again = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=0, **tiny.fast)
    assert again == trained
    other = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=1, **tiny.fast)
    assert other != trained
    a, b = load_monitor(tiny.root, trained).net, load_monitor(tiny.root, other).net
    assert not torch.equal(a.classifier.weight, b.classifier.weight)


def test_training_leaves_global_torch_state_alone(tiny) -> None:
    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    threads = torch.get_num_threads()
    train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=5, epochs=1)
    assert torch.equal(torch.rand(3), expected)
    assert torch.get_num_threads() == threads
    assert not torch.are_deterministic_algorithms_enabled()


def test_training_runs_with_deterministic_kernels_on() -> None:
    from evoeye.monitor.train import _reproducible

    with _reproducible(seed=0, threads=1):
        assert torch.are_deterministic_algorithms_enabled()
    assert not torch.are_deterministic_algorithms_enabled()


def test_card_records_data_hyperparameters_metrics_and_thresholds(
    tiny, trained: str
) -> None:
    card = read_card(tiny.root, trained)
    assert card["version"] == trained and card["name"] == "fusion" and card["parent"] is None
    assert card["selection"]["train"]["kind"] == "filter"
    params = card["selection"]["train"]["params"]
    assert params["logical_scenario"] == tiny.scenario and params["split"] == "train"
    assert card["data"]["train"]["runs"] == len(tiny.ids["train"]) == 6
    # val: one colliding run (frames 0 … 29, before its collision) and one safe run (40 frames)
    assert card["data"]["val"]["frames"] == 70 and card["data"]["val"]["unsafe_frames"] == 20
    assert len(card["data"]["train"]["fingerprint"]) == 16
    hp = card["hyperparameters"]
    assert hp["seed"] == 0 and hp["epochs"] == tiny.fast["epochs"] and hp["lr"] == tiny.fast["lr"]
    # negatives / positives of train: 3 × 30 + 3 × 40 frames before any collision, 60 unsafe
    assert hp["pos_weight"] == pytest.approx(150 / 60)
    assert card["horizon_s"] == tiny.horizon_s and card["context_len"] == 5
    assert 20_000 <= card["n_parameters"] <= 30_000
    assert set(card["thresholds"]) == {"0.05", "0.01"}
    assert card["thresholds"]["0.01"] >= card["thresholds"]["0.05"]
    val = card["metrics"]["val"]
    for key in ("fpr_0.05", "fpr_0.01"):
        m, cal = val[key], card["calibration"][key[4:]]
        assert m["fpr"] <= float(key[4:]) + 1e-9 and m["fpr"] == cal["realised_fpr"]
        assert m["threshold"] == card["thresholds"][key[4:]]
        assert m["reachable"] is cal["reachable"]
        assert 0.0 <= m["f1"] <= 1.0 if cal["reachable"] else m["f1"] is None
    assert 1 <= card["training"]["best_epoch"] <= card["training"]["epochs_run"]
    assert card["created_at"] and card["software_version"] and card["model_sha256"]


def test_card_thresholds_reproduce_the_target_fpr_on_val(tiny, trained: str) -> None:
    monitor = load_monitor(tiny.root, trained)
    val = load_windows(tiny.root, tiny.ids["val"], context_len=5, horizon_s=tiny.horizon_s)
    scores = monitor.score(val)
    for fpr in (0.05, 0.01):
        assert (scores[val.label == 0] > monitor.thresholds.at(fpr)).mean() <= fpr


def test_fine_tune_starts_from_the_parent_and_records_it(tiny, trained: str) -> None:
    child = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=0,
                          init_from=trained, epochs=1, patience=1, lr=1e-5)
    card = read_card(tiny.root, child)
    assert card["parent"] == trained and child != trained
    parent_net, child_net = load_monitor(tiny.root, trained).net, load_monitor(tiny.root, child).net
    # the parent's normalisers are kept, and one tiny step stays close to the parent's weights
    assert torch.equal(parent_net.norm["control"].mean, child_net.norm["control"].mean)
    diff = (parent_net.classifier.weight - child_net.classifier.weight).abs().max()
    assert 0 < float(diff.detach()) < 1e-3


def test_a_fine_tune_that_only_loses_keeps_its_parent(tiny, trained: str) -> None:
    def fine_tune(**keep) -> str:  # a learning rate that wrecks whatever it touches
        return train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=0,
                             init_from=trained, epochs=2, patience=2, lr=5.0, **keep)

    val = load_windows(tiny.root, tiny.ids["val"], context_len=5, horizon_s=tiny.horizon_s)

    def val_auprc(version: str) -> float:
        return ranking_metrics(load_monitor(tiny.root, version).score(val), val.label)["auprc"]

    wrecked = fine_tune()  # the default: the best of its own epochs, as Algorithm 1 trains
    assert wrecked != trained and val_auprc(wrecked) < val_auprc(trained)
    assert fine_tune(keep_parent=True) == trained  # no epoch beat it on val: kept


def test_fine_tune_refuses_a_different_architecture(tiny, trained: str) -> None:
    with pytest.raises(ValueError, match="parent"):
        train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, init_from=trained,
                      context_len=3, epochs=1)


def test_explicit_run_selections_and_module_ablation(tiny) -> None:
    version = train_monitor(
        tiny.root, train_runs=tiny.ids["train"], val_runs=RunFilter(split="val"),
        horizon_s=tiny.horizon_s, context_len=1, modules=("perception",), epochs=2)
    card = read_card(tiny.root, version)
    assert card["selection"]["train"]["kind"] == "ids"
    assert card["selection"]["train"]["count"] == 6
    assert card["modules"] == ["perception"] and card["context_len"] == 1
    assert set(load_monitor(tiny.root, version).net.encoders) == {"perception"}


def test_selection_without_unsafe_frames_is_refused(tiny) -> None:
    safe = "SELECT scenario_id FROM scenarios WHERE NOT collided"
    with pytest.raises(ValueError, match="both classes"):
        train_monitor(tiny.root, train_runs=safe, val_runs=tiny.ids["val"],
                      horizon_s=tiny.horizon_s, epochs=1)
    with pytest.raises(ValueError, match="scenario"):
        train_monitor(tiny.root)
