"""The nightly deployment: flat parameters a flow run overrides one at a time, a night with
nothing to do, the runs a killed serve process left, and its command line."""

from __future__ import annotations

import uuid

import pytest

from evoeye.store.feedback import read_rounds
from flows import deploy
from flows.deploy import NIGHTLY_CRON, nightly_deployment, nightly_evolution
from flows.evolve import EvolveParams

SCENARIO = "unprotected-intersection"  # the scenario of the `seeded` fixture (conftest)


def _client():
    from prefect.client.orchestration import get_client

    return get_client(sync_client=True)


def test_the_deployment_has_a_cron_and_each_field_as_a_parameter() -> None:
    params = EvolveParams(scenario=SCENARIO, strategy="uniform", budget_s=60, max_rounds=2)
    d = nightly_deployment(params)
    assert d.name == "nightly-evolution" and d.flow_name == "evoeye-evolve"
    assert deploy.deployment_name() == "evoeye-evolve/nightly-evolution"
    assert d.schedules[0].schedule.cron == NIGHTLY_CRON == "0 2 * * *"
    assert d.parameters == params.model_dump()  # flat: no `params` object to replace whole
    fields = d._parameter_openapi_schema.model_dump()["properties"]
    assert list(fields) == list(EvolveParams.model_fields)
    assert "avfuzzer" in fields["strategy"]["enum"] and fields["n_round"]["minimum"] == 1
    assert fields["budget_s"]["description"].startswith("Simulated seconds")
    assert d.concurrency_limit == 1


def test_a_flat_flow_run_validates_its_fields_as_evolve_params() -> None:
    from prefect.exceptions import ParameterTypeError, SignatureMismatchError

    given = nightly_evolution.validate_parameters({"budget_s": "800", "scenario": SCENARIO})
    assert EvolveParams(**given) == EvolveParams(budget_s=800, scenario=SCENARIO)
    with pytest.raises(ParameterTypeError, match="budget_s"):
        nightly_evolution.validate_parameters({"budget_s": -3})
    with pytest.raises(SignatureMismatchError):
        nightly_evolution.validate_parameters({"params": {"budget_s": 800}})


def _run(deployment_id, **overrides) -> tuple[dict, object]:
    """A flow run of the deployment as `prefect deployment run … --param k=v` makes it,
    run here to its end as serve would; (its result, the flow run as the server has it)."""
    from prefect.flow_engine import run_flow

    with _client() as client:
        run = client.create_flow_run_from_deployment(deployment_id, parameters=overrides)
    out = run_flow(nightly_evolution, flow_run=run, parameters=run.parameters)
    with _client() as client:
        return out, client.read_flow_run(run.id)


def test_a_run_overrides_one_parameter_and_keeps_the_others_and_says_when_it_has_nothing_to_do(
        prefect_server, seeded, monkeypatch, tmp_path) -> None:
    from prefect.client.schemas.filters import LogFilter, LogFilterFlowRunId
    from prefect.logging.handlers import APILogWorker

    root, g0 = seeded
    monkeypatch.setenv("EVOEYE_HOME", str(tmp_path / "not-the-root"))  # were root dropped
    params = EvolveParams(root=str(root.path), scenario=SCENARIO, strategy="uniform", seed=5,
                          budget_s=10, monitor=g0, n_round=3, epochs=1, train_frac=0.5,
                          val_frac=0.25, max_rounds=1, assess=False)
    deployment_id = nightly_deployment(params, name=f"overrides-{uuid.uuid4().hex[:6]}").apply()
    # 10 s: no run fits (one may last 20 s), so the night has nothing to do, and says so
    idle, run = _run(deployment_id)
    assert idle["nothing_to_do"] and idle["rounds"] == [] and run.state.is_completed()
    assert idle["message"].startswith(f"nothing to do: campaign {idle['campaign_id']} has "
                                      "spent its budget") and "budget_s" in idle["message"]
    APILogWorker.drain_all(timeout=10)  # the logs Prefect still queues for the API
    with _client() as client:
        logs = client.read_logs(LogFilter(flow_run_id=LogFilterFlowRunId(any_=[run.id])))
    assert any(log.message == idle["message"] for log in logs)
    # one field overridden: the deployment's others (root, strategy, N_round …) are kept
    out, run = _run(deployment_id, budget_s=100)
    assert run.parameters == {**params.model_dump(), "budget_s": 100}
    assert out["campaign_id"] == idle["campaign_id"] and not out["nothing_to_do"]
    assert out["root"] == str(root.path) and [r["round"] for r in out["rounds"]] == [1]
    rows = read_rounds(root, out["campaign_id"])
    assert [r.round for r in rows] == [0, 1] and len(rows[1].scenario_ids) == 3


def _set(client, run_id, state):
    return client.set_flow_run_state(run_id, state).state


def test_serve_marks_the_runs_a_killed_serve_left_crashed_and_frees_the_slot(
        prefect_server) -> None:
    from prefect import task
    from prefect.states import Completed, Pending, Running

    from flows.evolve import round_flow

    name = f"crash-{uuid.uuid4().hex[:6]}"
    deployment_id = nightly_deployment(EvolveParams(scenario=SCENARIO), name=name).apply()
    with _client() as client:  # a night and its round, Running when their serve was killed
        night = client.create_flow_run_from_deployment(deployment_id)
        assert _set(client, night.id, Pending()).is_pending()  # takes the one slot
        assert _set(client, night.id, Running()).is_running()
        parent = client.create_task_run(task(lambda: None, name="round"), night.id, "round-1")
        child = client.create_flow_run(round_flow, name="round-1-x", parent_task_run_id=parent.id,
                                       state=Running())
        # while they hold the slot, a new run of the deployment is cancelled
        held = client.create_flow_run_from_deployment(deployment_id)
        assert _set(client, held.id, Pending()).is_cancelled()
    assert sorted(deploy.crash_left_runs(name)) == sorted(
        [f"{night.name} (running)", "round-1-x (running)"])
    with _client() as client:
        assert client.read_flow_run(night.id).state.is_crashed()
        assert client.read_flow_run(child.id).state.is_crashed()
        after = client.create_flow_run_from_deployment(deployment_id)
        assert _set(client, after.id, Pending()).is_pending()  # not cancelled: the slot is free
        assert _set(client, after.id, Running()).is_running()
        _set(client, after.id, Completed())
    assert deploy.crash_left_runs(name) == []  # a finished run is left alone
    assert deploy.crash_left_runs("never-deployed") == []


def test_one_serve_process_per_deployment(prefect_server) -> None:
    name = f"lock-{uuid.uuid4().hex[:6]}"
    with deploy.serve_lock(name), pytest.raises(RuntimeError, match="another process serves"):
        deploy.serve_lock(name)
    deploy.serve_lock(name).close()  # free again once the first is closed


@pytest.fixture
def served(monkeypatch) -> list:
    """What `deploy.main` would serve, after what (nothing runs, nothing is contacted)."""
    calls: list = []
    monkeypatch.setattr(deploy, "configured_api_url", lambda: "http://127.0.0.1:1/api")
    monkeypatch.setattr(deploy, "crash_left_runs", lambda: calls.append("crash_left_runs"))
    monkeypatch.setattr("prefect.serve", calls.append)
    return calls


def test_serve_defaults_to_a_few_rounds_a_night_and_the_default_strategy(served) -> None:
    from evoeye.evolve.campaign import config

    deploy.main(["--scenario", SCENARIO])
    assert served[0] == "crash_left_runs"  # before anything is served
    params = served[1].parameters
    assert params["max_rounds"] == deploy.NIGHTLY_ROUNDS == 5  # not the whole budget at once
    assert params["budget_s"] == deploy.NIGHTLY_BUDGET_S and params["assess"] is True
    assert params["strategy"] == config.DEFAULT_STRATEGY
    deploy.main(["--scenario", SCENARIO, "--rounds-per-night", "2", "--cron", "0 3 * * *"])
    assert served[3].parameters["max_rounds"] == 2
    assert served[3].schedules[0].schedule.cron == "0 3 * * *"


def test_serve_explains_its_options_and_needs_a_server(served, monkeypatch, capsys) -> None:
    with pytest.raises(SystemExit):
        deploy.main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--max-rounds INT, --rounds-per-night INT Rounds per night" in text
    assert "(default: 5)" in text and "(default: 21600.0)" in text
    monkeypatch.setattr(deploy, "configured_api_url", lambda: None)
    with pytest.raises(SystemExit) as stopped:
        deploy.main(["--scenario", SCENARIO])
    assert stopped.value.code == 2 and "prefect server start" in capsys.readouterr().err
    assert served == []  # refused before anything is served
