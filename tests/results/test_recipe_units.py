"""A study's training recipe: in the ledger keys of the units that depend on it (the legacy
recipe's keys as before recipes had names), and seeds trained together where the family can."""

from __future__ import annotations

from dataclasses import replace

import pytest

from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.monitor.registry import read_card
from evoeye.results import units
from evoeye.results.config import ResultsConfig
from evoeye.results.rq2 import G0_RECIPE
from evoeye.results.study import Study

SCENARIO = "highway-cut-in"


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory, results_root_builder):
    return results_root_builder(tmp_path_factory.mktemp("recipes") / "data")


def _study(root, recipe: str) -> Study:
    return Study(root, ResultsConfig(scenarios=(SCENARIO,), training_seeds=(0, 1, 2),
                                     test_runs=0, test_batch="held", epochs=1, patience=1,
                                     recipe=recipe))


def _inputs(study: Study, seed: int) -> dict:
    """A training unit's inputs as they were before recipes had names."""
    return {"family": DEFAULT_FAMILY, **study.data_key(SCENARIO, "train", "val"), "seed": seed,
            "recipe": G0_RECIPE, "overrides": study.train_overrides}


def test_the_legacy_recipe_keeps_the_keys_and_others_say_theirs(root) -> None:
    v1, v2 = _study(root, "v1"), _study(root, "v2")
    old = units.trained_versions(v1, SCENARIO, DEFAULT_FAMILY, seeds=[0, 1], **G0_RECIPE)
    assert [v1.ledger.get("train", _inputs(v1, s)) for s in (0, 1)] == old
    new = units.trained_versions(v2, SCENARIO, DEFAULT_FAMILY, seeds=[0, 1], **G0_RECIPE)
    assert v2.ledger.get("train", {**_inputs(v2, 0), "training_recipe": "v2"}) == new[0]
    assert not set(old) & set(new)  # a v1 unit is never taken for a v2 one, nor back
    assert [read_card(root, v)["recipe"] for v in old + new] == ["v1"] * 2 + ["v2"] * 2
    # a recipe-less family keeps its keys whatever the study's recipe
    assert v2.recipe_key("context-only") == {} and v2.recipe_kwargs("context-only") == {}
    assert v2.recipe_key("aem") == {"training_recipe": "v2"} and FAMILIES["aem"].recipes


def test_seeds_trained_together_are_the_seeds_trained_one_by_one(root, monkeypatch) -> None:
    study = _study(root, "v2")
    calls: list[list[int]] = []
    fusion = FAMILIES[DEFAULT_FAMILY]
    together = fusion.train_seeds

    def spy(*args, seeds, **kwargs):
        calls.append(list(seeds))
        return together(*args, seeds=seeds, **kwargs)

    monkeypatch.setitem(FAMILIES, DEFAULT_FAMILY, replace(fusion, train_seeds=spy))
    versions = units.trained_versions(study, SCENARIO, DEFAULT_FAMILY, seeds=[0, 1, 2],
                                      context_len=1, modules=G0_RECIPE["modules"])
    assert calls == [[0, 1, 2]]  # none was in the ledger: all three at once
    assert units.trained_versions(study, SCENARIO, DEFAULT_FAMILY, seeds=[2, 0, 1],
                                  context_len=1, modules=G0_RECIPE["modules"]) == [
        versions[2], versions[0], versions[1]] and calls == [[0, 1, 2]]  # found, not trained
    monkeypatch.setattr(study.ledger, "folder", root.path / "other-ledger")
    one = [units.trained_version(study, SCENARIO, DEFAULT_FAMILY, seed=s, context_len=1,
                                 modules=G0_RECIPE["modules"]) for s in (0, 1, 2)]
    assert one == versions and calls == [[0, 1, 2]]


def test_rq1_trains_the_context_a_lookahead_recipe_fixes(root) -> None:
    from evoeye.monitor.recipes import RECIPE_NETWORKS
    from evoeye.results.rq1 import FULL_CONTEXT_LEN, fusion_context_len

    # RQ1's FusionMonitor passes its context to the training: under a lookahead recipe it is
    # the recipe's own (a fixed L = 5 trained another network than the recipe's)
    assert fusion_context_len("lookahead-v1") == RECIPE_NETWORKS["lookahead-v1"]["context_len"]
    assert fusion_context_len("lookahead-v1") == 20 and fusion_context_len("v3") == FULL_CONTEXT_LEN
    # and the study loads its windows long enough for it
    assert _study(root, "v3").context_len == max(FULL_CONTEXT_LEN, *ResultsConfig().context_lens)
    assert _study(root, "lookahead-v1").context_len == 20
