"""RQ2, the evolution ablations and AEM-Evo over paired campaign seeds, on three sets.

Campaigns run (or resume) through the experiment API (`evoeye.evolve.campaign.experiment`),
side by side over `workers` local processes: every method runs on the same campaign seeds, from
the same G_0 — the study's FusionMonitor of its first training seed — with the same budget, so
methods are compared seed by seed.

**Each final monitor is judged by the mean over k training seeds** (`final_seeds`), not by one
training and not as a k-seed ensemble: the last update (G_{R-1} fine-tuned, or retrained, on
D_R with the fixed val split) is done again with k − 1 other seeds, and each campaign's figure
is the mean of the k monitors' figures. The mean keeps the estimand — what one run of the method
gives a user, who deploys one monitor — and only removes the last training's seed noise from
it; an ensemble would judge a different, stronger monitor than any method produces. A campaign
that made no round keeps its start, G_0, judged by the mean of G_0's recipe over k seeds.

With `final="retrain"` the k monitors are instead G_0's recipe trained from scratch on the
campaign's D_R (D_init's train runs and every run it acquired) with the k training seeds of
"G_0 (k seeds)": a campaign and that row then differ only in their data, so the comparison
judges what a strategy acquired apart from how the update rule used it.

The sets (`units.judge`: an `Assessor` given the re-seeded G_0s): the Test Set (the study's
test split: the held-out batch), the paper's Hard Set (the unsafe test frames G_0 misses, plus
the safe frames of their runs) and the robust Hard Set (the unsafe test frames a majority of k
re-seeded G_0s — G_0's recipe with the study's first k training seeds, G_0 the first — miss,
plus every safe test frame). RQ2 thus trains k G_0s whatever the number of training seeds RQ1
and the monitor ablation use, and its units stay valid when that number grows. Rows: "G_0"
(the start of every campaign, one value), "G_0 (k seeds)" (G_0's recipe, no new data, mean of k
training seeds: the no-new-data control), and likewise "<family> G_0" for a `<family>-evo` method
(AEM-Evo's start: the AEM trained on D_init).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from functools import cache

import numpy as np

from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import (
    campaigns_of,
    method_of,
    methods,
    plan_experiment,
    run_experiment,
)
from evoeye.evolve.campaign.loop import Campaign
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.monitor.inputs import MODULES
from evoeye.results.rq1 import FULL_CONTEXT_LEN
from evoeye.results.study import Study
from evoeye.results.units import judge, set_figures, trained_versions
from evoeye.store.feedback import read_rounds
from evoeye.store.selection import RunFilter

FINAL_SEED_STRIDE = 100_000  # seed of final retraining j: the last update's seed + j × stride
# G_0's recipe: RQ1's full FusionMonitor (a family that has no modules, e.g. the AEM, ignores them)
G0_RECIPE = {"context_len": FULL_CONTEXT_LEN, "modules": list(MODULES)}
G0, G0_SEEDS = "G_0", "G_0 (k seeds)"


def g0_label(family: str, seeds: bool = False) -> str:
    """The row of a family's start ("G_0", "AEM G_0") or of its recipe over k seeds."""
    base = G0 if family == DEFAULT_FAMILY else f"{FAMILIES[family].label} {G0}"
    return f"{base} (k seeds)" if seeds else base


def mean_figures(figures: Sequence[dict]) -> dict:
    """The mean over several monitors' {set: metrics} of every numeric metric (undefined ones —
    an unreachable target's F1, AUROC on one class — left out; None where none is defined); a
    target FPR is reachable if any of the monitors reached it."""
    out: dict = {}
    for name in figures[0]:
        out[name] = {}
        for key in figures[0][name]:
            values = [f[name][key] for f in figures if f[name].get(key) is not None]
            if key.startswith("reachable@"):
                out[name][key] = any(values)
            else:
                out[name][key] = float(np.mean(values)) if values else None
    return out


def _retrain_last_update(study: Study, cfg: CampaignConfig, previous: str, j: int) -> str:
    """The campaign's last update (from `previous` = G_{R-1}) done again with seed offset j."""
    family = FAMILIES[cfg.family]

    def reseeded(root, scenario, *, seed: int, **kwargs) -> str:
        return family.train(root, scenario, seed=seed + j * FINAL_SEED_STRIDE, **kwargs)

    campaign = Campaign(study.root, cfg, train=reseeded)
    state = campaign.start()
    study.say(f"  {campaign.campaign_id}: final update again, seed offset {j}")
    # the state as the last update saw it: G_{R-1}, its round not yet stored (replay's
    # new runs are those of no stored round)
    version, _ = campaign.update_monitor(replace(state, round=state.round - 1,
                                                 monitor=previous, rounds=state.rounds[:-1]))
    return version


def _campaign_data(study: Study, cfg: CampaignConfig) -> tuple[list[str], RunFilter]:
    """The campaign's D_R (its initial train runs and every run it acquired that ran) and its
    fixed val split."""
    campaign = Campaign(study.root, cfg)
    state = campaign.start()
    return [str(s) for s in state.records.scenario_id[state.ok]], campaign.val_runs


def final_versions(study: Study, cfg: CampaignConfig, campaign_id: str,
                   start_seeds: Sequence[str]) -> list[str]:
    """The k monitors a campaign's final figure is the mean of (module doc)."""
    rounds = read_rounds(study.root, campaign_id)
    last = rounds[-1]
    k = study.config.final_seeds
    if last.round == 0:  # D_R = D_init: both kinds of final are G_0's recipe over k seeds
        return list(start_seeds[:k])
    family = FAMILIES[cfg.family]

    def exists(version: str) -> bool:
        return family.version_dir(study.root, version).is_dir()

    if study.config.final == "retrain":
        data = cache(lambda: _campaign_data(study, cfg))  # read once, for the k seeds

        def retrain(seed: int) -> str:
            ids, val = data()
            study.say(f"  {campaign_id}: G_0's recipe on its D_R ({len(ids)} runs), seed {seed}")
            return family.train(study.root, cfg.scenario, train_runs=ids, val_runs=val,
                                seed=seed, splits=cfg.splits, horizon_s=cfg.horizon_s,
                                **G0_RECIPE, **study.train_overrides,
                                **study.recipe_kwargs(cfg.family))

        return [study.ledger.remember(
            "final-retrain", {"campaign": campaign_id, "last": last.monitor_version,
                              "seed": seed, "recipe": G0_RECIPE,
                              "overrides": study.train_overrides,
                              **study.recipe_key(cfg.family)},
            lambda seed=seed: retrain(seed), valid=exists)
            for seed in study.config.training_seeds[:k]]
    out = [last.monitor_version]
    for j in range(1, k):
        inputs = {"campaign": campaign_id, "final": last.monitor_version, "j": j}
        out.append(study.ledger.remember(
            "final", inputs,
            lambda j=j: _retrain_last_update(study, cfg, rounds[-2].monitor_version, j),
            valid=exists))
    return out


def rq2(study: Study, scenario: str) -> dict:
    """Run (or resume) every campaign of the scenario, then judge them (module doc)."""
    cfg = study.config
    k = cfg.final_seeds
    g0s = trained_versions(study, scenario, DEFAULT_FAMILY, seeds=cfg.training_seeds[:k],
                           **G0_RECIPE)  # the k re-seeded G_0s, G_0 first (module doc)
    base = CampaignConfig(scenario, monitor=g0s[0], n_round=cfg.n_round, update=cfg.update,
                          feedback=cfg.feedback, epochs=cfg.epochs, patience=cfg.patience,
                          horizon_s=cfg.horizon_s, splits=study.splits, recipe=cfg.recipe)
    study.say(f"{scenario}: RQ2 campaigns {list(cfg.methods)} × seeds {list(cfg.campaign_seeds)}")
    plan = plan_experiment(study.root, [scenario], base, strategies=cfg.methods,
                           seeds=cfg.campaign_seeds, budget_s=cfg.budget_s)
    ran = run_experiment(study.root, [scenario], base, strategies=cfg.methods,
                         seeds=cfg.campaign_seeds, budget_s=cfg.budget_s, controls=0,
                         progress=study.say, workers=cfg.workers, plan=plan).get(scenario, {})
    sets = judge(study, scenario, g0s)
    n = len(cfg.campaign_seeds)
    families = [DEFAULT_FAMILY] + sorted({methods()[m][1] for m in cfg.methods} - {DEFAULT_FAMILY})
    seeds_of = {f: g0s if f == DEFAULT_FAMILY else trained_versions(
        study, scenario, f, seeds=cfg.training_seeds[:k], **G0_RECIPE) for f in families}
    rows: dict[str, dict] = {}
    campaigns = campaigns_of(study.root, plan)
    starts = {DEFAULT_FAMILY: g0s[0]}
    for campaign in campaigns:
        if campaign.config.family != DEFAULT_FAMILY:
            starts.setdefault(campaign.config.family, campaign.g0)
    for f in families:
        start = set_figures(study, sets, starts[f])
        rows[g0_label(f)] = {"versions": [[starts[f]]] * n, "figures": [start] * n}
        per_seed = [set_figures(study, sets, v) for v in seeds_of[f]]
        rows[g0_label(f, seeds=True)] = {"versions": [seeds_of[f]], "figures": per_seed,
                                         "unpaired": True}
    acquired = {(r["seed"], m): r for m, runs in ran.items() if isinstance(runs, list)
                for r in runs}
    for campaign in campaigns:
        c, campaign_id = campaign.config, campaign.campaign_id
        method = method_of(c)
        versions = final_versions(study, c, campaign_id, seeds_of[c.family])
        row = rows.setdefault(method, {"campaigns": [], "versions": [], "figures": [],
                                       "acquisition": []})
        row["campaigns"].append(campaign_id)
        row["versions"].append(versions)
        row["figures"].append(mean_figures([set_figures(study, sets, v) for v in versions]))
        row["acquisition"].append(acquired.get((c.seed, method), {}).get("acquisition"))
    return {"campaign_seeds": list(cfg.campaign_seeds), "final_seeds": k, "g0": g0s[0],
            "reseeded": g0s, "sets": sets.sizes(), "methods": rows}
