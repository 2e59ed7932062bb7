"""The monitors of a learning curve: trained from scratch, updated by the product's rule,
scored for the strategies' feedback, and judged on the sets no strategy shaped.

Nothing is saved: a monitor lives as long as its curve (the ledger keeps its figures). Every
monitor is early-stopped and calibrated on the regime's validation set, trained with one
intra-op thread (`evoeye.monitor.threads`), and seeded, so the same runs and seed give the same
monitor. A checkpoint's monitor (`Learner.checkpoint`) is one such monitor, or with
`members` > 1 an ensemble of that many (`evoeye.monitor.ensemble`), calibrated as one.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from evoeye.evolve.campaign.assess import metrics_dict
from evoeye.evolve.campaign.config import REPLAY_EPOCHS, REPLAY_PATIENCE, REPLAY_RATIO
from evoeye.evolve.search.feedback import scenario_disagreement, scenario_feedback
from evoeye.monitor.ensemble import EnsembleMonitor, member_seeds
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.recipes import TrainParams, recipe_key, recipe_params
from evoeye.monitor.train import fit_windows
from evoeye.store.windows import Windows


@dataclass
class Learner:
    """Trains, updates, scores and judges FusionMonitors against fixed val and judging sets."""

    val: Windows
    judging: dict[str, Windows]  # set name → windows (the Test Set, the boundary set)
    params: TrainParams = field(default_factory=recipe_params)  # the seed is given per call
    members: int = 1  # of every checkpoint's monitor (`checkpoint`)
    # set name → per-window weights of a judging set that is a stratified sample (none: each
    # window counts once; `evoeye.evaluation.metrics.frame_metrics`)
    judging_weights: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def recipe(self) -> dict:
        """The training recipe (every hyper-parameter but the seed), for ledger keys."""
        return recipe_key(self.params)

    def scratch(self, train: Windows, seed: int,
                weights: Mapping[str, float] | None = None) -> FusionMonitor:
        """A FusionMonitor trained from scratch on `train` with `seed` (with the recipe's
        `importance_weights`, each run weighted by its p/q in `weights`)."""
        return self._monitor(fit_windows(train, self.val, replace(self.params, seed=seed),
                                         run_weights=self._weights(weights)),
                             f"scratch-{seed}")

    def checkpoint(self, train: Windows, seed: int,
                   weights: Mapping[str, float] | None = None,
                   first: FusionMonitor | None = None) -> FusionMonitor | EnsembleMonitor:
        """A checkpoint's monitor on `train`: `scratch` with `seed` (`first`, if that monitor
        was trained already), or with `members` > 1 the ensemble of it and `members` − 1 more
        from scratch with the seeds `member_seeds` derives from `seed`."""
        return self.as_checkpoint(self.committee(train, seed, self.members, weights, first), seed)

    def committee(self, train: Windows, seed: int, k: int,
                  weights: Mapping[str, float] | None = None,
                  first: FusionMonitor | None = None) -> list[FusionMonitor]:
        """k monitors from scratch on `train` with the seeds `member_seeds(seed, k)` (member 0:
        `first`, if trained already); its first `members` are the checkpoint's members."""
        seeds = member_seeds(seed, k)
        return [first or self.scratch(train, seed, weights),
                *(self.scratch(train, s, weights) for s in seeds[1:])]

    def as_checkpoint(self, committee: list[FusionMonitor],
                      seed: int) -> FusionMonitor | EnsembleMonitor:
        """The checkpoint's monitor of a `committee` trained with `seed` (`committee`): its
        member 0 alone, or its first `members` as an ensemble calibrated as one monitor."""
        if len(committee) < self.members:
            raise ValueError(f"a checkpoint needs {self.members} members, got {len(committee)}")
        if self.members == 1:
            return committee[0]
        return EnsembleMonitor.calibrated(committee[: self.members], self.val,
                                          f"ensemble-{seed}x{self.members}")

    def update(self, parent: FusionMonitor, train: Windows, seed: int,
               weights: Mapping[str, float] | None = None) -> FusionMonitor:
        """The paper's update rule (`evoeye evolve --update replay`): `parent` fine-tuned for
        at most REPLAY_EPOCHS on `train` (the round's runs and their replay sample)."""
        params = replace(self.params, seed=seed, epochs=REPLAY_EPOCHS, patience=REPLAY_PATIENCE)
        return self._monitor(fit_windows(train, self.val, params, parent=parent.net,
                                         run_weights=self._weights(weights)),
                             f"{parent.version}+{seed}")

    def _weights(self, weights: Mapping[str, float] | None) -> Mapping[str, float] | None:
        return weights if self.params.importance_weights else None

    def _monitor(self, trained, version: str) -> FusionMonitor:
        card = {"hyperparameters": {"pos_weight": trained.result.pos_weight}}
        return FusionMonitor(trained.result.net, version, trained.thresholds, card)

    def judge(self, monitor: FusionMonitor | EnsembleMonitor) -> dict[str, dict]:
        """{set: metrics} of the monitor on every judging set, at its calibrated thresholds."""
        return {name: metrics_dict(monitor.score(w), w.label, monitor.thresholds,
                                   self.judging_weights.get(name))
                for name, w in self.judging.items()}


def run_feedback(monitor: FusionMonitor, windows: Windows) -> dict[str, float]:
    """f_r per run: the mean |ŷ − y| over the run's windows (the paper's feedback)."""
    fb = scenario_feedback(monitor.score(windows), windows.label, windows.scenario_id)
    return dict(zip(fb.scenario_id.tolist(), fb.feedback.tolist(), strict=True))


def run_disagreement(committee: list[FusionMonitor], windows: Windows) -> dict[str, float]:
    """Per run, the mean over its windows of the spread of the committee's scores."""
    scores = np.stack([m.score(windows) for m in committee])  # (K, B)
    d = scenario_disagreement(scores, windows.scenario_id)
    return dict(zip(d.scenario_id.tolist(), d.feedback.tolist(), strict=True))


def replay_sample(earlier: np.ndarray, earlier_collided: np.ndarray, n_new: int,
                  new_collided: bool, rng: np.random.Generator) -> np.ndarray:
    """Indices (sorted) of the earlier runs an update replays beside n_new new ones: as many
    as REPLAY_RATIO asks, at least one collision among them when the new runs have none and
    an earlier run has one (the campaign's rule, `Campaign.training_runs`)."""
    k = min(len(earlier), int(round(REPLAY_RATIO * n_new)))
    pick = np.sort(rng.choice(len(earlier), size=k, replace=False))
    if k and not earlier_collided[pick].any() and not new_collided and earlier_collided.any():
        pick[0:1] = rng.choice(np.flatnonzero(earlier_collided), size=1)
    return np.sort(pick)
