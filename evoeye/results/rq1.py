"""RQ1 and the monitor ablation over the study's training seeds.

Per logical scenario and training seed s: the full FusionMonitor (every module input; L = 5, or
the context the study's recipe fixes, `fusion_context_len`) trained with seed s,
each trained baseline (AEM, the context-only control) fitted with seed s, and the rules (TTC,
TTC-2D, RSS, RSS-2s), which have no seed and so the same figures for every s. The ablation
trains every variant (L ∈ context_lens with every input; the input subsets at L = 5) with the
same seeds; its "L=5" row is the RQ1 FusionMonitor (the same units, where the recipe fixes no
context), its reference rows are the RQ1 baselines that `ablation.REFERENCES` names. Methods
and variants trained with the same seed on the same data are compared pair by pair
(`evoeye.results.tables`). A recipe's seeds the ledger lacks train together
(`units.trained_versions`): the same versions.
"""

from __future__ import annotations

from evoeye.evaluation.ablation import REFERENCES, input_sets, variants
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.monitor.inputs import MODULES
from evoeye.results.study import Study
from evoeye.results.units import baseline, test_figures, trained_versions, trains

FUSION_LABEL = FAMILIES[DEFAULT_FAMILY].label  # "FusionMonitor"
FULL_CONTEXT_LEN = 5


def fusion_context_len(recipe: str) -> int:
    """RQ1's FusionMonitor context: the one `recipe`'s network fixes (lookahead-v1's), else
    FULL_CONTEXT_LEN."""
    from evoeye.monitor.recipes import RECIPE_NETWORKS

    return RECIPE_NETWORKS.get(recipe, {}).get("context_len", FULL_CONTEXT_LEN)


def _fusion_rows(study: Study, scenario: str, context_len: int,
                 modules: tuple[str, ...]) -> dict:
    """One FusionMonitor recipe over the training seeds: versions and figures per seed."""
    fusion = FAMILIES[DEFAULT_FAMILY]
    versions = trained_versions(study, scenario, DEFAULT_FAMILY,
                                seeds=study.config.training_seeds, context_len=context_len,
                                modules=list(modules))
    return {"versions": versions,
            "figures": [test_figures(study, scenario, fusion.load(study.root, v))
                        for v in versions]}


def _baseline_rows(study: Study, scenario: str, name: str) -> dict:
    """A baseline over the training seeds (a rule: one evaluation, the same for every seed)."""
    seeds = study.config.training_seeds
    if not trains(name):
        monitor = baseline(study, scenario, name, seeds[0])
        figures = test_figures(study, scenario, monitor)
        return {"versions": [monitor.version] * len(seeds), "figures": [figures] * len(seeds)}
    monitors = [baseline(study, scenario, name, seed) for seed in seeds]
    return {"versions": [m.version for m in monitors],
            "figures": [test_figures(study, scenario, m) for m in monitors]}


def rq1(study: Study, scenario: str) -> dict:
    """{"seeds", "methods": {name: {"versions", "figures"}}}: the FusionMonitor, then every
    baseline of the config, each with one entry per training seed."""
    study.say(f"{scenario}: RQ1 over training seeds {list(study.config.training_seeds)}")
    methods = {FUSION_LABEL: _fusion_rows(
        study, scenario, fusion_context_len(study.config.recipe), MODULES)}
    for name in study.config.baselines:
        methods[name] = _baseline_rows(study, scenario, name)
    return {"seeds": list(study.config.training_seeds), "methods": methods}


def ablation(study: Study, scenario: str) -> dict:
    """{"seeds", "methods": {label: {"versions", "figures"}}}: every variant, then the
    reference baselines (those of REFERENCES the config evaluates)."""
    study.say(f"{scenario}: monitor ablation over training seeds "
              f"{list(study.config.training_seeds)}")
    sets = input_sets()
    methods = {v.label: _fusion_rows(study, scenario, v.context_len, sets[v.inputs])
               for v in variants(study.config.context_lens, study.config.inputs)}
    for name in REFERENCES:
        if name in study.config.baselines:
            methods[name] = _baseline_rows(study, scenario, name)
    return {"seeds": list(study.config.training_seeds), "methods": methods}
