"""Preparing an experiment: each campaign's round 0 stored once, before the workers start."""

from __future__ import annotations

import pytest

from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.workers import CampaignJob, prepare_campaigns
from evoeye.store import SplitSpec
from evoeye.store.feedback import read_feedback, read_rounds

SCENARIO = "unprotected-intersection"  # of the `seeded` data root (conftest.py)
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)


def test_preparing_campaigns_stores_round_0_once_without_building_their_state(
        root_copy, seeded, monkeypatch) -> None:
    root = root_copy("prepare")
    cfg = CampaignConfig(scenario=SCENARIO, strategy="uniform", budget_s=50.0, seed=0,
                         monitor=seeded[1], n_round=2, epochs=1, splits=SPLITS)
    monkeypatch.setattr(Campaign, "_acquired", lambda self, ids: pytest.fail("state built"))
    job = CampaignJob(str(root.path), cfg, "uniform seed 0")
    prepare_campaigns([job])
    first = read_rounds(root, Campaign(root, cfg).campaign_id)
    assert [(r.round, r.monitor_version, r.scenario_ids) for r in first] == [(0, seeded[1], [])]
    assert first[0].metrics is not None and first[0].metrics.test  # G_0 assessed
    fed = read_feedback(root).num_rows
    assert fed > 0  # G_0's feedback on D_init
    prepare_campaigns([job])  # a prepared (or finished) campaign: nothing stored again
    assert read_rounds(root, Campaign(root, cfg).campaign_id) == first
    assert read_feedback(root).num_rows == fed
