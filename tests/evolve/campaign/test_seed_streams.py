"""A campaign never acquires a run the root already holds: its own seed streams, then a redraw."""

from __future__ import annotations

import numpy as np
from campaign_helpers import SCENARIO, config

from evoeye.batch import plan_uniform, simulate_and_log
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.state import redrawn_note, run_seed
from evoeye.evolve.search.registry import make_strategy
from evoeye.scenarios import get_scenario
from evoeye.seeds import campaign_run_seed, search_seed
from evoeye.sim.runner import run_spec
from evoeye.store import Warehouse, ingest

INITIAL_SEED = 6  # the seeded root's initial batch (conftest)


def _batch_ids(root, batch: str) -> list[str]:
    return Warehouse(root).sql("SELECT scenario_id FROM scenarios WHERE batch = ?",
                               [batch]).column(0).to_pylist()


def test_the_old_stream_met_the_batch_and_the_new_one_does_not() -> None:
    space = get_scenario(SCENARIO)
    first = plan_uniform(SCENARIO, 1, INITIAL_SEED)[0]
    old = make_strategy("uniform", space, INITIAL_SEED).propose()
    assert run_spec(SCENARIO, old.x, run_seed(INITIAL_SEED, 0)).scenario_id == first.scenario_id
    a, b = "evo-uniform-s6-aaaa", "evo-avfuzzer-s6-bbbb"  # two campaigns' ids
    new = make_strategy("uniform", space, search_seed(INITIAL_SEED, a)).propose()
    assert not np.allclose(new.x, first.params)
    assert campaign_run_seed(INITIAL_SEED, a, 0) != first.seed
    assert len({campaign_run_seed(INITIAL_SEED, a, 0), campaign_run_seed(INITIAL_SEED, a, 1),
                campaign_run_seed(INITIAL_SEED, a, 0, attempt=1),
                campaign_run_seed(INITIAL_SEED, b, 0)}) == 4
    # two campaigns at one seed: the old streams gave AV-Fuzzer's first member Uniform's first
    ga = make_strategy("avfuzzer", space, search_seed(INITIAL_SEED, b)).propose()
    assert not np.allclose(ga.x, new.x)


def test_uniform_campaign_at_the_batch_seed_acquires_no_held_run(root_copy, seeded) -> None:
    root = root_copy("same-seed")
    before = set(Warehouse(root).sql("SELECT scenario_id FROM scenarios").column(0).to_pylist())
    c = Campaign(root, config(seeded[1], strategy="uniform", seed=INITIAL_SEED, n_round=3))
    state = c.start()
    row = c.run_round(state)
    assert state.redrawn == []
    assert not before & set(row.scenario_ids)
    assert sorted(_batch_ids(root, c.campaign_id)) == sorted(row.scenario_ids)
    assert row.n_records == len(row.scenario_ids) == 3


def test_a_proposal_the_root_holds_is_redrawn_and_reported(root_copy, seeded) -> None:
    root = root_copy("planted")
    c = Campaign(root, config(seeded[1], strategy="uniform", seed=2, n_round=2))
    x = make_strategy("uniform", get_scenario(SCENARIO), search_seed(2, c.campaign_id)
                      ).propose().x
    planted = run_spec(SCENARIO, x, campaign_run_seed(2, c.campaign_id, 0), batch="planted")
    simulate_and_log(planted, root)
    ingest(root)
    state = c.start()
    row = c.run_round(state)
    assert state.redrawn == [(planted.scenario_id, "planted")]
    assert planted.scenario_id not in row.scenario_ids
    assert sorted(_batch_ids(root, c.campaign_id)) == sorted(row.scenario_ids)
    assert len(row.scenario_ids) == row.n_records == 2
    note = redrawn_note(state)
    assert planted.scenario_id in note and "batch planted" in note
    # the redrawn run has the proposal's vector and another seed
    got = Warehouse(root).sql("SELECT params, seed FROM scenarios WHERE scenario_id = ?",
                              [row.scenario_ids[0]]).to_pylist()[0]
    np.testing.assert_array_equal(got["params"], x)
    assert got["seed"] == campaign_run_seed(2, c.campaign_id, 0, attempt=1)


def test_two_campaigns_of_one_strategy_and_seed_share_no_run(root_copy, seeded) -> None:
    root = root_copy("paired")
    ids = []
    for update in ("retrain", "replay"):  # two campaign ids, one strategy, one seed
        c = Campaign(root, config(seeded[1], strategy="uniform", seed=0, n_round=2,
                                  update=update))
        row = c.run_round(c.start())
        assert sorted(_batch_ids(root, c.campaign_id)) == sorted(row.scenario_ids)
        ids.append(set(row.scenario_ids))
    assert len(ids[0]) == len(ids[1]) == 2 and not ids[0] & ids[1]
