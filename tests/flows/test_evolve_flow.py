"""The evolution flow through Prefect: a flow run per round (`round-<r>-…`); the nightly
deployment is in test_deploy.py."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from evoeye.store.feedback import read_rounds
from flows.evolve import EvolveParams, evolution_flow

SCENARIO = "unprotected-intersection"  # the scenario of the `seeded` fixture (conftest)


def test_params_reject_unknown_strategy() -> None:
    with pytest.raises(ValidationError, match="strategy"):
        EvolveParams(strategy="grid")
    with pytest.raises(ValidationError, match="budget_s"):
        EvolveParams(budget_s=-1)
    with pytest.raises(ValidationError, match="unknown feedback"):
        EvolveParams(feedback="calibrated")
    with pytest.raises(ValidationError, match="unknown update"):
        EvolveParams(update="lukewarm")


def test_round_tasks_pass_parameters_and_run_ids_not_state() -> None:
    import inspect

    from flows import evolve

    for task in (evolve.acquire, evolve.ingest_round, evolve.train, evolve.score):
        kinds = {p.annotation for p in inspect.signature(task.fn).parameters.values()}
        assert kinds <= {"CampaignRun", "list[str]", "str", "float"}, (task.name, kinds)


def test_params_are_the_campaign_options_and_give_back_the_config() -> None:
    from evoeye.evolve.campaign.config import CampaignConfig, campaign_options

    assert {o.name for o in campaign_options()} <= set(EvolveParams.model_fields)
    cfg = CampaignConfig(SCENARIO, strategy="avfuzzer", seed=2, n_round=3, patience=2)
    params = EvolveParams.of(cfg, "/r", max_rounds=1)
    assert params.config() == cfg and params.root == "/r" and params.max_rounds == 1


def test_one_constant_is_the_default_strategy_of_evolve_and_its_flow() -> None:
    """DEFAULT_STRATEGY is what `evoeye evolve` and EvolveParams run (and the nightly
    deployment: test_deploy.py)."""
    import inspect

    from evoeye.cli.evolve import evolve_command
    from evoeye.evolve.campaign import config

    assert config.DEFAULT_STRATEGY == "evoeye"
    assert config.CampaignConfig().strategy == config.DEFAULT_STRATEGY
    assert EvolveParams().strategy == config.DEFAULT_STRATEGY
    assert inspect.signature(evolve_command).parameters["strategy"].default \
        == config.DEFAULT_STRATEGY


def test_evolution_flow_runs_each_round_as_a_flow_run(seeded, latest_artifact) -> None:
    from datetime import UTC, datetime

    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import (
        FlowRunFilter,
        FlowRunFilterName,
        FlowRunFilterStartTime,
    )

    root, g0 = seeded
    started = datetime.now(UTC)  # other tests (the demo flow's) run rounds of this name too
    params = EvolveParams(root=str(root.path), scenario=SCENARIO, strategy="evoeye", budget_s=1000,
                          monitor=g0, n_round=3, epochs=1, max_rounds=2, train_frac=0.5,
                          val_frac=0.25, assess=True)
    out = evolution_flow(params)
    assert out["round"] == 2 and len(out["rounds"]) == 2
    rows = read_rounds(root, out["campaign_id"])
    assert [r.round for r in rows] == [0, 1, 2]
    assert [len(r.scenario_ids) for r in rows] == [0, 3, 3]
    assert all(r.metrics.hard["frames"] >= 0 for r in rows)  # every G_r assessed
    names = [f"round-{r}-{SCENARIO}-evoeye-s0" for r in (1, 2)]
    since = FlowRunFilterStartTime(after_=started)
    with get_client(sync_client=True) as client:
        runs = client.read_flow_runs(flow_run_filter=FlowRunFilter(
            name=FlowRunFilterName(any_=names), start_time=since))
        campaign = client.read_flow_runs(flow_run_filter=FlowRunFilter(
            name=FlowRunFilterName(any_=[f"evolve-{SCENARIO}-evoeye-s0"]), start_time=since))
    assert sorted(r.name for r in runs) == names and len(campaign) == 1
    assert all(r.state.is_completed() for r in runs)
    # the campaign's artifact (the newest: other tests' flows publish theirs on the same server):
    # its rounds with each G_r's figures in %, and what changed
    artifact = latest_artifact("evoeye-evolve")
    assert f"# Evolution: {SCENARIO}, evoeye, seed 0" in artifact
    assert "| Round | New runs | Sim s | Monitor | Test F1@.05 % |" in artifact
    assert f"| 2 | 3 | {rows[2].simulated_s:.0f} | {rows[2].monitor_version} |" in artifact
    assert "2 round(s) added 6 runs" in artifact and "Hard-Set F1@0.05" in artifact
    # a second flow run with a higher max resumes the same campaign at round 3
    out2 = evolution_flow(params.model_copy(update={"max_rounds": 1}))
    assert out2["campaign_id"] == out["campaign_id"] and out2["round"] == 3


def test_a_campaign_with_no_budget_is_refused_before_anything_runs() -> None:
    with pytest.raises(ValueError, match="budget_s must be greater than 0"):
        EvolveParams(scenario=SCENARIO, budget_s=0)
