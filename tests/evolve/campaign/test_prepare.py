"""Preparing an experiment: each campaign's round 0 stored once, before the workers start."""

from __future__ import annotations

import pytest

from evoeye.evolve.campaign import loop
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import campaigns_of
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.workers import CampaignJob, prepare_campaigns, run_campaign
from evoeye.store import SplitSpec
from evoeye.store.feedback import read_feedback, read_rounds

SCENARIO = "unprotected-intersection"  # of the `seeded` data root (conftest.py)
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)


def test_preparing_campaigns_stores_round_0_once_without_building_their_state(
        root_copy, seeded, monkeypatch) -> None:
    root = root_copy("prepare")
    cfg = CampaignConfig(scenario=SCENARIO, strategy="uniform", budget_s=50.0, seed=0,
                         monitor=seeded[1], n_round=2, epochs=1, splits=SPLITS)
    monkeypatch.setattr(loop, "acquired_runs", lambda *a: pytest.fail("state built"))
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


def test_a_finished_campaign_is_not_resumed_by_its_worker(root_copy, seeded,
                                                          monkeypatch) -> None:
    root = root_copy("finished")
    cfg = CampaignConfig(scenario=SCENARIO, strategy="uniform", budget_s=50.0, seed=0,
                         monitor=seeded[1], n_round=2, epochs=1, splits=SPLITS)
    job = CampaignJob(str(root.path), cfg, "uniform seed 0")
    campaign = Campaign(root, cfg)
    assert not campaign.finished()  # nothing stored yet
    prepare_campaigns([job])
    assert not campaign.finished()  # round 0 spent nothing
    done = run_campaign(job)
    rounds = read_rounds(root, campaign.campaign_id)
    assert done.rounds == len(rounds) - 1 > 0
    state = Campaign(root, cfg).start()
    assert campaign.done(state) and campaign.finished()  # the same verdict, without a state
    assert state.spent_s == pytest.approx(rounds[-1].simulated_s)
    monkeypatch.setattr(loop, "acquired_runs", lambda *a: pytest.fail("state built"))
    again = run_campaign(job)
    assert again.rounds == 0 and read_rounds(root, campaign.campaign_id) == rounds


def test_the_campaigns_of_a_plan_read_d_init_once(root_copy, seeded, monkeypatch) -> None:
    from evoeye.store import Warehouse

    root = root_copy("of-plan")
    plan = [CampaignConfig(scenario=SCENARIO, strategy=s, budget_s=50.0, seed=seed,
                           monitor=seeded[1], n_round=2, epochs=1, splits=SPLITS)
            for s in ("uniform", "evoeye") for seed in (0, 1)]
    alone = [Campaign(root, cfg) for cfg in plan]
    expected = [(c.campaign_id, list(c.initial["scenario_id"])) for c in alone]
    reads: list[str] = []
    query = Warehouse.query
    monkeypatch.setattr(Warehouse, "query",
                        lambda self, name, **kw: reads.append(name) or query(self, name, **kw))
    shared = campaigns_of(root, plan)
    assert [(c.campaign_id, list(c.initial["scenario_id"])) for c in shared] == expected
    assert reads.count("initial_records") == 1
    other = CampaignConfig(scenario=SCENARIO, strategy="uniform", budget_s=50.0, seed=0,
                           monitor=seeded[1], n_round=2, epochs=1,
                           splits=SplitSpec(seed=1, train_frac=0.5, val_frac=0.25))
    mixed = campaigns_of(root, [plan[0], other])  # another split: read again
    assert reads.count("initial_records") == 3
    assert mixed[1].campaign_id != mixed[0].campaign_id == expected[0][0]


def test_a_resumed_campaign_says_its_stored_rounds_again(root_copy, seeded) -> None:
    root = root_copy("resumed-lines")
    cfg = CampaignConfig(scenario=SCENARIO, strategy="uniform", budget_s=100.0, seed=0,
                         monitor=seeded[1], n_round=2, epochs=1, splits=SPLITS)
    job = CampaignJob(str(root.path), cfg, "uniform seed 0")
    prepare_campaigns([job])
    Campaign(root, cfg).run(max_rounds=1)  # a worker that stored round 1, then died
    assert not Campaign(root, cfg).finished()
    said: list[str] = []
    done = run_campaign(job, brief=lambda m: "M", say=said.append)
    assert said[0] == "uniform seed 0 round 1: M | stored before this worker resumed it"
    assert said[1:] == list(done.lines) and done.lines[0].startswith("uniform seed 0 round 2: ")
    assert done.rounds == len(read_rounds(root, Campaign(root, cfg).campaign_id)) - 2
