"""The evolution flow through Prefect: rounds are `round-<r>` flow runs; the nightly deployment."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from evoeye.store.feedback import read_rounds
from flows.deploy import NIGHTLY_CRON, nightly_deployment
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
        EvolveParams(update="warm")


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


def test_nightly_deployment_has_cron_and_parameter_schema() -> None:
    d = nightly_deployment(EvolveParams(scenario=SCENARIO, strategy="uniform", budget_s=60))
    assert d.name == "nightly-evolution"
    assert d.schedules[0].schedule.cron == NIGHTLY_CRON == "0 2 * * *"
    assert d.parameters["params"]["strategy"] == "uniform"
    schema = d._parameter_openapi_schema.model_dump()
    fields = schema["definitions"]["EvolveParams"]["properties"]
    assert {"scenario", "strategy", "budget_s", "seed", "n_round", "max_rounds"} <= set(fields)
    assert "avfuzzer" in fields["strategy"]["enum"]
    assert d.concurrency_limit == 1


def test_one_constant_is_the_default_strategy_of_evolve_its_flow_and_the_nightly_run(
        monkeypatch) -> None:
    """DEFAULT_STRATEGY is what `evoeye evolve`, EvolveParams and the deployment run."""
    import inspect

    from evoeye.cli.evolve import evolve_command
    from evoeye.evolve.campaign import config
    from flows import deploy

    assert config.DEFAULT_STRATEGY == "evoeye"
    assert config.CampaignConfig().strategy == config.DEFAULT_STRATEGY
    assert EvolveParams().strategy == config.DEFAULT_STRATEGY
    assert inspect.signature(evolve_command).parameters["strategy"].default \
        == config.DEFAULT_STRATEGY
    served = {}
    monkeypatch.setattr("prefect.serve", lambda d: served.setdefault("d", d))
    deploy.main(["--scenario", SCENARIO])
    assert served["d"].parameters["params"]["strategy"] == config.DEFAULT_STRATEGY


def test_evolution_flow_runs_each_round_as_a_flow_run(prefect_server, seeded) -> None:
    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import FlowRunFilter, FlowRunFilterName

    root, g0 = seeded
    params = EvolveParams(root=str(root.path), scenario=SCENARIO, strategy="evoeye", budget_s=1000,
                          monitor=g0, n_round=3, epochs=1, max_rounds=2, train_frac=0.5,
                          val_frac=0.25, assess=True)
    out = evolution_flow(params)
    assert out["round"] == 2 and len(out["rounds"]) == 2
    rows = read_rounds(root, out["campaign_id"])
    assert [r.round for r in rows] == [0, 1, 2]
    assert [len(r.scenario_ids) for r in rows] == [0, 3, 3]
    assert all(r.metrics.hard["frames"] >= 0 for r in rows)  # every G_r assessed
    with get_client(sync_client=True) as client:
        runs = client.read_flow_runs(flow_run_filter=FlowRunFilter(
            name=FlowRunFilterName(any_=["round-1", "round-2"])))
    assert sorted(r.name for r in runs) == ["round-1", "round-2"]
    assert all(r.state.is_completed() for r in runs)
    # a second flow run with a higher max resumes the same campaign at round 3
    out2 = evolution_flow(params.model_copy(update={"max_rounds": 1}))
    assert out2["campaign_id"] == out["campaign_id"] and out2["round"] == 3
