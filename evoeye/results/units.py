"""The units a study is made of — train a monitor, fit a baseline, judge a version — each kept
in the ledger by its inputs, so a re-run finds it instead of doing it again.

A unit's figures are `{set: metrics}` with the metrics of `assess.metrics_dict` (F1, precision
and recall at each target FPR — None where the target was unreachable — AUROC, AUPRC, frame
counts): set "test" for RQ1 and the ablation; "test", "hard" and "robust" for RQ2. Monitors
score with one intra-op thread, as campaigns do (`evoeye.monitor.threads`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evoeye.evaluation.harness import score_and_calibrate
from evoeye.evaluation.monitors import BASELINES
from evoeye.evolve.campaign.assess import FPRS, Assessor, metrics_dict
from evoeye.monitor.families import FAMILIES, MonitorFamily, family_of
from evoeye.monitor.protocol import Monitor
from evoeye.monitor.threads import intra_op_threads
from evoeye.results.study import Study


def _exists(study: Study, family: MonitorFamily):
    return lambda version: family.version_dir(study.root, version).is_dir()


def trained_version(study: Study, scenario: str, family: str, *, seed: int,
                    **recipe) -> str:
    """A version of `family` trained from scratch on the round-0 train split, early-stopped and
    calibrated on val, with this seed and recipe (e.g. context_len, modules)."""
    return trained_versions(study, scenario, family, seeds=[seed], **recipe)[0]


def trained_versions(study: Study, scenario: str, family: str, *, seeds: Sequence[int],
                     **recipe) -> list[str]:
    """`trained_version` of each seed; those the ledger lacks are trained together where the
    family can (`MonitorFamily.train_seeds`: the same versions as one by one, bit for bit)."""
    fam = FAMILIES[family]
    data = study.data_key(scenario, "train", "val")
    kwargs = {"train_runs": study.runs(scenario, "train"), "val_runs": study.runs(scenario, "val"),
              "splits": study.splits, "horizon_s": study.config.horizon_s, **recipe,
              **study.train_overrides, **study.recipe_kwargs(family)}

    def inputs(seed: int) -> dict:
        return {"family": family, **data, "seed": seed, "recipe": recipe,
                "overrides": study.train_overrides, **study.recipe_key(family)}

    def say(seeds: Sequence[int]) -> None:
        study.say(f"{scenario}: training {fam.label} seed{'s' * (len(seeds) > 1)} "
                  f"{', '.join(map(str, seeds))} {recipe or ''}".rstrip())

    def found(seed: int) -> bool:
        version = study.ledger.get("train", inputs(seed))
        return version is not None and _exists(study, fam)(version)

    missing = [s for s in seeds if not found(s)]
    done: dict[int, str] = {}
    if len(missing) > 1 and fam.train_seeds is not None:
        say(missing)
        done = dict(zip(missing, fam.train_seeds(study.root, scenario, seeds=missing, **kwargs),
                        strict=True))

    def train(seed: int) -> str:
        if seed in done:
            return done[seed]
        say([seed])
        return fam.train(study.root, scenario, seed=seed, **kwargs)

    return [study.ledger.remember("train", inputs(s), lambda s=s: train(s),
                                  valid=_exists(study, fam)) for s in seeds]


def trains(name: str) -> bool:
    """Whether baseline `name` is trained (a family with an RQ1 fit: its seed matters)."""
    return name in FAMILIES and FAMILIES[name].fit is not None


def baseline(study: Study, scenario: str, name: str, seed: int) -> Monitor:
    """A baseline by name: a rule, or a trained family fitted on the round-0 train split with
    this seed."""
    if not trains(name):
        return BASELINES[name](study.root, scenario, study.splits)
    fam = FAMILIES[name]
    inputs = {"baseline": name, **study.data_key(scenario, "train"), "seed": seed,
              **study.recipe_key(name)}
    def fit() -> str:
        study.say(f"{scenario}: fitting {name} seed {seed}")
        return fam.fit(study.root, scenario, study.splits, seed=seed,
                       runs=study.runs(scenario, "train"),
                       horizon_s=study.config.horizon_s, **study.recipe_kwargs(name)).version

    return fam.load(study.root, study.ledger.remember("fit", inputs, fit,
                                                      valid=_exists(study, fam)))


def test_figures(study: Study, scenario: str, monitor: Monitor) -> dict:
    """RQ1's figures of a monitor: thresholds calibrated on val (the FPR each realises there
    kept), metrics on the test split."""
    inputs = {"version": monitor.version, **study.data_key(scenario, "val", "test")}

    @intra_op_threads()
    def evaluate() -> dict:
        study.say(f"{scenario}: evaluating {monitor.name} {monitor.version}")
        test = study.windows(scenario, "test")
        c = score_and_calibrate(monitor, study.windows(scenario, "val"), test, FPRS)
        figures = metrics_dict(c.test, test.windows.label, c.thresholds)
        figures.update({f"val_fpr@{f}": c.thresholds.realised_fpr[f] for f in FPRS})
        return {"test": figures}

    return study.ledger.remember("evaluate", inputs, evaluate)


def judge(study: Study, scenario: str, g0s: Sequence[str]) -> Assessor:
    """RQ2's sets on one scenario's test split: the Test Set, the paper's Hard Set of
    G_0 = g0s[0] and the robust Hard Set of all of `g0s` (the k re-seeded G_0s, G_0 first)."""
    return Assessor(study.root, scenario, g0s[0], reseeded=g0s, splits=study.splits,
                    horizon_s=study.config.horizon_s, test=study.windows(scenario, "test"))


def set_metrics(scores: np.ndarray, labels: np.ndarray, thresholds) -> dict:
    """`metrics_dict` of one set; only its sizes where it holds no unsafe frame (every rate of
    it is undefined then, not 0)."""
    if not labels.any():
        return {"frames": int(len(labels)), "unsafe": 0}
    return metrics_dict(scores, labels, thresholds)


def set_figures(study: Study, sets: Assessor, version: str) -> dict:
    """A version's figures on the Test Set, the Hard Set and the robust Hard Set (`judge`), at
    the thresholds it was calibrated at when trained."""
    inputs = {"version": version, **study.data_key(sets.scenario, "test"), "g0": sets.g0,
              "reseeded": list(sets.reseeded)}
    return study.ledger.remember("assess", inputs, lambda: sets.figures(version, set_metrics),
                                 valid=lambda _: _exists(study, family_of(version))(version))
