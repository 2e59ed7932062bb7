"""The `disagreement` strategy's committee: G_r and K − 1 companion monitors trained beside it.

A run's disagreement is the mean over its contexts of the spread of the K members' scores
(`scenario_disagreement`, on ŷ as the campaign's feedback mode takes it); the strategy regresses
it on θ (`evoeye.evolve.search.disagreement`). The members after round r:
* round 0: G_0 and K − 1 FusionMonitors trained from scratch on D_init with G_0's recipe (its
  context length and training hyper-parameters) and seeds 2001, 2002, … (`from_scratch` finds
  them again by their card, so every campaign of the scenario and split shares them);
* round r + 1: G_{r+1}, and each companion updated from its own round-r self as G_r is
  (`--update`), on the same runs, with its own seed.
The companions of each round are the `committee` table; the disagreement of every run under
G_r's committee is stored as feedback rows of mode `disagreement-k<K>[-prior-corrected]` under
G_r, so a resumed campaign reads them instead of scoring again.

Cost, per round: K monitor updates instead of one, and the new runs and the refresh scored K
times (BENCHMARKS.md, "The committee's cost in a campaign").
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from evoeye.evolve.campaign.config import DEFAULT_RECIPE, LEGACY_RECIPE
from evoeye.evolve.campaign.scoring import mode_scores
from evoeye.evolve.search.feedback import ScenarioFeedback, scenario_disagreement
from evoeye.paths import DataRoot
from evoeye.store import RunFilter
from evoeye.store.feedback import feedback_of, read_committee, write_committee
from evoeye.store.selection import SplitSpec
from evoeye.store.windows import Windows, load_windows

if TYPE_CHECKING:
    from evoeye.evolve.campaign.loop import Campaign
    from evoeye.evolve.campaign.state import CampaignState

COMMITTEE_SEED = 2000  # round-0 companion j is trained from scratch with seed 2000 + j
COMPANION_SEED_STRIDE = 1_000_000  # companion j's update seeds: G_r's + j · stride
RECIPE = ("epochs", "patience", "batch_size", "lr", "weight_decay", "grad_clip")  # of G_0's card


def from_scratch(root: DataRoot, scenario: str, ids: Sequence[str], val_runs: RunFilter,
                 seed: int, splits: SplitSpec, horizon_s: float,
                 context_len: int | None = None, recipe: str = DEFAULT_RECIPE,
                 **params: Any) -> str:
    """The FusionMonitor trained from scratch on runs `ids` with `seed` (the training
    `recipe` and TrainParams `params` over it): a version already trained so (same scenario,
    runs, seed, recipe, params and, if given, context length) is reused, else it is trained."""
    from evoeye.monitor import list_versions, read_card, train_monitor
    from evoeye.monitor.card import describe_selection

    selection = describe_selection(list(ids))
    for version in list_versions(root):
        card = read_card(root, version)
        if (card.get("logical_scenario") == scenario and not card.get("parent")
                and card.get("selection", {}).get("train") == selection
                and card.get("hyperparameters", {}).get("seed") == seed
                and context_len in (None, card.get("context_len"))
                and card.get("recipe", LEGACY_RECIPE) == recipe
                and all(card["hyperparameters"].get(k) == v for k, v in params.items())):
            return version
    return train_monitor(root, scenario, train_runs=list(ids), val_runs=val_runs, seed=seed,
                         splits=splits, horizon_s=horizon_s, context_len=context_len,
                         recipe=recipe, **params)


class Committee:
    """The committee of one campaign (`Campaign.committee`, for strategies that read the
    records' disagreement)."""

    def __init__(self, campaign: Campaign) -> None:
        self.campaign = campaign
        self.k = campaign.config.committee

    @property
    def mode(self) -> str:
        """The feedback mode its disagreement is stored under."""
        feedback = self.campaign.config.feedback
        return f"disagreement-k{self.k}" + ("" if feedback == "raw" else f"-{feedback}")

    def companions(self, round_: int) -> list[str]:
        """Members 1 .. K − 1 after round `round_` (round 0's are found or trained, and
        stored, on first use)."""
        c = self.campaign
        stored = read_committee(c.root, c.campaign_id)
        if round_ in stored:
            return stored[round_]
        if round_ != 0:
            raise LookupError(f"{c.campaign_id}: no committee stored for round {round_}")
        cfg, ids = c.config, [str(s) for s in c.initial["scenario_id"]]
        g0 = c.monitor(c.g0)
        card = g0.card or {}
        params = {k: v for k, v in card.get("hyperparameters", {}).items() if k in RECIPE}
        versions = [from_scratch(c.root, cfg.scenario, ids, c.val_runs, COMMITTEE_SEED + j,
                                 cfg.splits, cfg.horizon_s, g0.context_len,
                                 card.get("recipe", LEGACY_RECIPE), **params)
                    for j in range(1, self.k)]
        write_committee(c.root, c.campaign_id, 0, versions)
        return read_committee(c.root, c.campaign_id)[0]

    def disagreement(self, members: Sequence[str], windows: Windows) -> ScenarioFeedback:
        """Per run of `windows`: the members' mean spread."""
        c = self.campaign
        scores = np.stack([mode_scores(c.monitor(v), windows, c.config.feedback)
                           for v in members])  # (K, B)
        return scenario_disagreement(scores, windows.scenario_id)

    def stored(self, primary: str) -> dict[str, float]:
        """scenario_id → disagreement stored under the committee of G_r = `primary`."""
        return feedback_of(self.campaign.root, primary, self.mode)

    def store(self, primary: str, round_: int, scenario_ids: Sequence[str]) -> None:
        """Score ingested runs with the committee after round `round_` (G_r = `primary`) and
        store their disagreement (runs already stored are skipped)."""
        c = self.campaign
        have = self.stored(primary)
        todo = [str(s) for s in scenario_ids if s not in have]
        if not todo:
            return
        with c.clock("refresh"):
            windows = load_windows(c.root, todo, context_len=c.monitor(primary).context_len,
                                   horizon_s=c.config.horizon_s)
            d = self.disagreement([primary, *self.companions(round_)], windows)
        c.write_feedback(primary, d.scenario_id, d.feedback, d.n_contexts, mode=self.mode)

    def update(self, state: CampaignState, ids: Sequence[str]) -> None:
        """Train and store the companions after round state.round + 1 on `ids` (G_{r+1}'s
        runs; none: the round's companions stay), unless they are stored already."""
        c, cfg, r = self.campaign, self.campaign.config, state.round + 1
        if r in read_committee(c.root, c.campaign_id):
            return
        before = self.companions(state.round)
        fine_tune = cfg.update != "retrain"
        versions = [c.train_monitor_version(
            list(ids), seed=cfg.seed * 1000 + r + COMPANION_SEED_STRIDE * j,
            init_from=previous if fine_tune else None, state=state) if ids else previous
            for j, previous in enumerate(before, start=1)]
        write_committee(c.root, c.campaign_id, r, versions)
