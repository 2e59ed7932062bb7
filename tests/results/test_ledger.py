"""The ledger: a unit is done once per inputs, found again by a re-run, redone when invalid."""

from __future__ import annotations

import numpy as np

from evoeye.paths import DataRoot
from evoeye.results.ledger import Ledger


def test_a_unit_is_computed_once_and_found_by_the_next_ledger(tmp_path) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    calls = []

    def compute() -> dict:
        calls.append(1)
        return {"auroc": np.float64(0.75), "f1@0.05": None, "versions": ("a", "b")}

    inputs = {"scenario": "s", "seed": 3, "recipe": {"L": 5}}
    first = Ledger(root).remember("train", inputs, compute)
    again = Ledger(root)  # a re-run: a new process, the same folder
    assert again.remember("train", {"recipe": {"L": 5}, "seed": 3, "scenario": "s"},
                          compute) == first  # the inputs' order does not matter
    assert first == {"auroc": 0.75, "f1@0.05": None, "versions": ["a", "b"]}  # JSON types
    assert len(calls) == 1 and again.found["train"] == 1 and not again.computed
    again.remember("train", {**inputs, "seed": 4}, compute)  # other inputs: another unit
    again.remember("evaluate", inputs, compute)  # another kind: another unit
    assert len(calls) == 3 and again.computed == {"train": 1, "evaluate": 1}


def test_an_output_that_no_longer_holds_is_computed_again(tmp_path) -> None:
    ledger = Ledger(DataRoot.resolve(tmp_path / "data"))
    assert ledger.remember("train", {"x": 1}, lambda: "v1") == "v1"
    assert ledger.remember("train", {"x": 1}, lambda: "v2", valid=lambda v: v != "v1") == "v2"
    assert ledger.get("train", {"x": 1}) == "v2"


def test_a_file_of_other_inputs_is_not_taken_for_the_unit(tmp_path) -> None:
    ledger = Ledger(DataRoot.resolve(tmp_path / "data"))
    ledger.put("train", {"x": 1}, "v1")
    path = ledger.path("train", {"x": 1})
    path.write_text(path.read_text().replace('"x": 1', '"x": 2'))  # a hand-edited entry
    assert ledger.get("train", {"x": 1}) is None
