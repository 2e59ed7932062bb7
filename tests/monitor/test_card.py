"""Card helpers: metrics on hand-checked inputs, selection descriptions, data fingerprints."""

from __future__ import annotations

import json

import numpy as np
import pytest

from evoeye.monitor.card import (
    describe_selection,
    ranking_metrics,
    split_metrics,
    threshold_metrics,
    thresholds_from_card,
    thresholds_from_json,
    thresholds_to_card,
    thresholds_to_json,
)
from evoeye.monitor.protocol import Thresholds
from evoeye.store import RunFilter


def test_threshold_metrics_count_alarms_above_the_threshold() -> None:
    scores = np.array([0.9, 0.8, 0.3, 0.7, 0.2, 0.1])
    labels = np.array([1, 1, 1, 0, 0, 0])
    m = threshold_metrics(scores, labels, 0.5)  # alarms: 0.9, 0.8 (tp) and 0.7 (fp)
    assert m["precision"] == pytest.approx(2 / 3) and m["recall"] == pytest.approx(2 / 3)
    assert m["f1"] == pytest.approx(2 / 3) and m["fpr"] == pytest.approx(1 / 3)
    assert threshold_metrics(scores, labels, 0.9)["f1"] == 0.0  # no alarm: score > 0.9 only


def test_ranking_metrics_and_a_split_without_positives() -> None:
    assert ranking_metrics(np.array([0.1, 0.9]), np.array([0, 1])) == {"auroc": 1.0,
                                                                       "auprc": 1.0}
    assert ranking_metrics(np.array([0.1, 0.9]), np.array([0, 0])) == {"auroc": None,
                                                                       "auprc": None}
    out = split_metrics(np.array([0.1, 0.9]), np.array([0, 1]), Thresholds({0.05: 0.5}))
    assert out["fpr_0.05"]["f1"] == 1.0


def test_thresholds_round_trip_through_json() -> None:
    thr = Thresholds({0.05: 0.25, 0.01: 0.75})
    as_json = thresholds_to_json(thr)
    assert as_json == {"0.05": 0.25, "0.01": 0.75}
    assert thresholds_from_json(as_json) == thr


def test_calibration_round_trips_through_a_card_and_old_cards_still_load() -> None:
    thr = Thresholds({0.05: 0.25, 0.01: 1.0}, {0.05: 0.049, 0.01: 0.0}, frozenset({0.01}))
    card = json.loads(json.dumps(thresholds_to_card(thr)))
    assert card["thresholds"] == {"0.05": 0.25, "0.01": 1.0}  # the format older readers know
    assert card["calibration"]["0.01"] == {"realised_fpr": 0.0, "reachable": False}
    assert thresholds_from_card(card) == thr
    old = thresholds_from_card({"thresholds": {"0.05": 0.25, "0.01": 0.75}})
    assert old.at(0.01) == 0.75 and old.reachable(0.01) and old.realised_fpr == {}


def test_an_unreachable_target_has_no_rates_on_the_card() -> None:
    scores, labels = np.array([1.0, 1.0, 1.0, 0.2]), np.array([1, 0, 0, 0])
    thr = Thresholds({0.05: 1.0}, {0.05: 0.0}, frozenset({0.05}))
    m = split_metrics(scores, labels, thr)["fpr_0.05"]
    assert m["reachable"] is False and (m["precision"], m["recall"], m["f1"]) == (None,) * 3
    assert m["fpr"] == 0.0 and m["threshold"] == 1.0


def test_selections_are_described_without_storing_long_id_lists() -> None:
    f = describe_selection(RunFilter(logical_scenario="x", split="val"))
    assert f["kind"] == "filter" and f["params"]["split"] == "val"
    assert describe_selection("SELECT 1")["query"] == "SELECT 1"
    ids = describe_selection(["b", "a"])
    assert ids["count"] == 2 and ids == describe_selection(["a", "b"])  # order-free
