"""The campaign's monitor updates: the runs each rule trains on, a failed round, the committee."""

from __future__ import annotations

import numpy as np
import pytest
from campaign_helpers import SCENARIO, SPLITS, config

from evoeye.evolve.campaign.config import WARM_EPOCHS
from evoeye.evolve.campaign.loop import Campaign
from evoeye.monitor.families import FAMILIES
from evoeye.store import load_windows
from evoeye.store.feedback import read_committee

# -- the replay update: each round trains on its runs and a seeded sample of as many earlier --

def capture_training(root, cfg, log: list[list[str]]) -> Campaign:
    """A campaign whose monitor updates are real, with the runs each one trained on logged."""
    def train(*args, train_runs, **kwargs) -> str:
        log.append(list(train_runs))
        return FAMILIES["fusion"].train(*args, train_runs=train_runs, **kwargs)
    return Campaign(root, cfg, train=train)


def test_replay_trains_on_the_rounds_runs_and_as_many_earlier_ones(root_copy, seeded) -> None:
    root = root_copy("replay")
    cfg = config(seeded[1], strategy="uniform", n_round=3, update="replay")
    trained: list[list[str]] = []
    c = capture_training(root, cfg, trained)
    state = c.run(max_rounds=2)
    initial = set(c.initial["scenario_id"])
    assert len(trained) == 2 and len(initial) > 3
    earlier = set(initial)
    for row, ids in zip(state.rounds[1:], trained, strict=True):
        new = [s for s, ok in zip(state.records.scenario_id, state.ok, strict=True)
               if ok and s in row.scenario_ids]
        assert len(new) == 3 and ids[-3:] == new  # the round's own runs, in order, last
        replayed = ids[:-3]
        assert len(replayed) == 3 and len(set(replayed)) == 3 and set(replayed) <= earlier
        collided = dict(zip(state.records.scenario_id, state.records.collided, strict=True))
        assert any(collided[s] for s in ids)  # both classes to learn from
        earlier |= set(row.scenario_ids)

    again: list[list[str]] = []  # the same campaign elsewhere draws the same samples
    capture_training(root_copy("replay-again"), cfg, again).run(max_rounds=2)
    assert again == trained


def test_finetune_trains_on_every_record(root_copy, seeded) -> None:
    trained: list[list[str]] = []
    c = capture_training(root_copy("finetune"), config(seeded[1], strategy="uniform",
                                                       update="finetune"), trained)
    state = c.run(max_rounds=1)
    ok = [s for s, good in zip(state.records.scenario_id, state.ok, strict=True) if good]
    assert trained == [ok] and len(ok) == len(c.initial["scenario_id"]) + 2


def test_warm_trains_every_record_from_the_last_monitor_briefly(root_copy, seeded) -> None:
    calls: list[tuple[list[str], str | None, int]] = []

    def train(*args, train_runs, init_from, epochs, **kwargs) -> str:
        calls.append((list(train_runs), init_from, epochs))
        return FAMILIES["fusion"].train(*args, train_runs=train_runs, init_from=init_from,
                                        epochs=epochs, **kwargs)

    c = Campaign(root_copy("warm"), config(seeded[1], strategy="uniform", update="warm",
                                           epochs=None),
                 train=train)
    state = c.run(max_rounds=2)
    ok = [s for s, good in zip(state.records.scenario_id, state.ok, strict=True) if good]
    first, second = state.rounds[1].monitor_version, state.rounds[2].monitor_version
    assert [(parent, epochs) for _, parent, epochs in calls] == [
        (state.rounds[0].monitor_version, WARM_EPOCHS), (first, WARM_EPOCHS)]
    assert calls[1][0] == ok and len(ok) == len(c.initial["scenario_id"]) + 4
    assert second != first


def test_retrain_the_default_trains_from_scratch_on_every_record(root_copy, seeded) -> None:
    calls: list[tuple[list[str], str | None]] = []

    def train(*args, train_runs, init_from, **kwargs) -> str:
        calls.append((list(train_runs), init_from))
        return FAMILIES["fusion"].train(*args, train_runs=train_runs, init_from=init_from,
                                        **kwargs)

    c = Campaign(root_copy("retrain"), config(seeded[1], strategy="uniform"), train=train)
    assert c.config.update == "retrain"
    state = c.run(max_rounds=1)
    ok = [s for s, good in zip(state.records.scenario_id, state.ok, strict=True) if good]
    assert calls == [(ok, None)] and len(ok) == len(c.initial["scenario_id"]) + 2


@pytest.mark.parametrize("update", ["retrain", "replay", "finetune", "warm"])
def test_a_round_without_an_ok_run_keeps_its_monitor(root_copy, seeded, update: str) -> None:
    c = Campaign(root_copy("failed"), config(seeded[1], strategy="uniform", update=update))
    state = c.start()
    c.acquire(state)
    state.ok[:] = np.arange(len(state.ok)) < len(c.initial["scenario_id"])  # the round failed
    assert state.training_runs(c.config.update, c.config.seed) == []
    assert c.update_monitor(state) == (state.monitor, 0.0)


@pytest.mark.parametrize("update", ["retrain", "replay", "finetune", "warm"])
def test_records_without_a_collision_keep_the_monitor(root_copy, seeded, update: str) -> None:
    """A tiny D_r with no collision has one class only: training on it would fail."""
    c = Campaign(root_copy("no-collision"), config(seeded[1], strategy="uniform", update=update))
    state = c.start()
    c.acquire(state)
    assert state.training_runs(c.config.update, c.config.seed)  # a collision among them …
    state.records.collided[:] = False
    assert state.training_runs(c.config.update, c.config.seed) == []  # … and without one
    assert c.update_monitor(state) == (state.monitor, 0.0)


def test_disagreement_campaign_keeps_a_committee_and_each_runs_spread(root_copy, seeded) -> None:
    """K = 3: two companions per round, found again by later campaigns for round 0, and every
    record's disagreement is the spread of the committee's scores on its warehouse windows."""
    from evoeye.evolve.search.feedback import scenario_disagreement

    root = root_copy("committee")
    c = Campaign(root, config(seeded[1], strategy="disagreement", committee=3))
    state = c.run(max_rounds=2)
    committee = read_committee(root, c.campaign_id)
    assert sorted(committee) == [0, 1, 2] and all(len(v) == 2 for v in committee.values())
    assert len({*committee[0], *committee[1], *committee[2], *(r.monitor_version
                                                              for r in state.rounds)}) == 9
    ok = state.records.scenario_id[state.ok]
    w = load_windows(root, list(ok), context_len=5, horizon_s=3.0)
    members = [state.monitor, *committee[2]]
    expected = scenario_disagreement(np.stack([c.monitor(v).score(w) for v in members]),
                                     w.scenario_id)
    np.testing.assert_allclose(state.records.disagreement[state.ok],
                               expected.aligned(ok), rtol=1e-6)
    assert np.isfinite(state.records.disagreement[state.ok]).all()
    # another campaign of the same G_0 and D_init shares round 0's companions
    other = Campaign(root, config(seeded[1], strategy="disagreement", committee=3, seed=1))
    assert other.committee.companions(0) == committee[0]
    # the committee's size is part of a disagreement campaign's id, of no other
    assert Campaign(root, config(seeded[1], strategy="disagreement", committee=4)).campaign_id \
        != c.campaign_id
    assert Campaign(root, config(seeded[1], committee=4)).campaign_id \
        == Campaign(root, config(seeded[1])).campaign_id


def test_retraining_keeps_g0s_network_kinematics_and_inputs_included(root_copy, seeded) -> None:
    from evoeye.monitor import train_monitor
    from evoeye.monitor.registry import load_monitor

    root = root_copy("kinematics")
    g0 = train_monitor(root, SCENARIO, seed=0, splits=SPLITS, epochs=1, kinematics=True,
                       modules=("perception", "planning"))
    asked: list[dict] = []

    def train(*args, **kwargs) -> str:
        asked.append({k: kwargs.get(k) for k in ("context_len", "kinematics", "modules",
                                                 "init_from")})
        return FAMILIES["fusion"].train(*args, **kwargs)

    state = Campaign(root, config(g0, strategy="uniform"), train=train).run(max_rounds=1)
    assert asked == [{"context_len": 5, "kinematics": True,
                      "modules": ["perception", "planning"], "init_from": None}]
    g1 = load_monitor(root, state.monitor).net.config  # G_1 derives them too, on G_0's inputs
    assert g1.kinematics and g1.modules == ("perception", "planning")
    # a G_0 without them is retrained without them, as before
    plain: list[dict] = []
    Campaign(root_copy("plain"), config(seeded[1], strategy="uniform"),
             train=lambda *a, **k: plain.append(k) or FAMILIES["fusion"].train(*a, **k)
             ).run(max_rounds=1)
    assert plain[0]["kinematics"] is False and plain[0]["context_len"] == 5
