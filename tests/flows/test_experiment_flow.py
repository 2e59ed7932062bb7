"""The RQ2 experiment as a flow: every campaign a named evolution flow run, then the report."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest
from pydantic import ValidationError

from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import plan_experiment
from evoeye.evolve.campaign.loop import Campaign
from evoeye.monitor import list_versions
from evoeye.monitor.families import initial_monitor
from evoeye.store import SplitSpec
from evoeye.store.feedback import read_rounds
from flows.experiment import ExperimentParams, experiment_flow

SCENARIO = "unprotected-intersection"  # the scenario of the `seeded` fixture (conftest)
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)


def test_params_reject_unknown_names() -> None:
    with pytest.raises(ValidationError, match="grid"):
        ExperimentParams(strategies=["uniform", "grid"])
    with pytest.raises(ValidationError, match="mars"):
        ExperimentParams(scenarios=["mars"])
    with pytest.raises(ValidationError, match="repetitions"):
        ExperimentParams(repetitions=0)


def test_plan_is_seed_major_with_the_initial_data_budget(seeded) -> None:
    root, g0 = seeded
    base = CampaignConfig(SCENARIO, splits=SPLITS)
    plan = plan_experiment(root, [SCENARIO], base, strategies=["uniform", "evoeye"], seeds=[0, 1])
    assert [(c.seed, c.strategy) for c in plan] == [
        (0, "uniform"), (0, "evoeye"), (1, "uniform"), (1, "evoeye")]
    assert {c.monitor for c in plan} == {g0}
    d_init = Campaign(root, base).initial["duration_s"]
    assert len(d_init) > 0
    assert [c.budget_s for c in plan] == pytest.approx([d_init.sum()] * 4)
    fixed = plan_experiment(root, [SCENARIO], base, strategies=["uniform"], seeds=[0],
                            budget_s=45.0)
    assert fixed == [replace(plan[0], budget_s=45.0)]
    (aem,) = plan_experiment(root, [SCENARIO], base, strategies=["aem-evo"], seeds=[0])
    assert (aem.strategy, aem.family, aem.monitor, aem.reference) == ("evoeye", "aem", None, g0)
    with pytest.raises(ValueError, match="unknown method"):
        plan_experiment(root, [SCENARIO], base, strategies=["aem"], seeds=[0])


def test_experiment_flow_runs_named_campaigns_and_writes_the_report(prefect_server,
                                                                   seeded) -> None:
    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import TaskRunFilter, TaskRunFilterName

    root, g0 = seeded
    params = ExperimentParams(root=str(root.path), scenarios=[SCENARIO],
                              strategies=["uniform", "evoeye", "aem-evo"], repetitions=1,
                              budget_s=45.0,
                              n_round=2, epochs=1, train_frac=0.5, val_frac=0.25,
                              controls=1, report_name="rq2-test")
    out = experiment_flow(params)
    res = out["results"][SCENARIO]
    for strategy in ("uniform", "evoeye", "aem-evo"):
        (run,) = res[strategy]
        rows = read_rounds(root, run["campaign_id"])
        sizes = [len(r.scenario_ids) for r in rows]
        assert sizes[0] == 0 and all(1 <= n <= 2 for n in sizes[1:]) and len(sizes) > 1
        # run to the budget: spent, but never overspent (no run lasts more than 20 s)
        assert 45.0 - 20.0 < rows[-1].simulated_s <= 45.0 and run["budget_s"] == 45.0
        # round 0 is G_0's assessment, shared by all campaigns; AEM-Evo starts from its own AEM
        assert run["rounds"][0] == res["aem-initial" if strategy == "aem-evo" else "initial"]
        assert run["rounds"][-1]["hard"]["frames"] == res["initial"]["hard"]["frames"]
        assert set(run["rounds"][-1]) >= {"test", "hard"}
        assert run["acquisition"]["runs"] == sum(sizes)
    names = [f"unprotected-intersection-{m}-s0" for m in ("uniform", "evoeye", "aem-evo")]
    with get_client(sync_client=True) as client:  # one task run per campaign, side by side
        runs = client.read_task_runs(task_run_filter=TaskRunFilter(
            name=TaskRunFilterName(any_=names)))
    assert sorted(r.name for r in runs) == sorted(names)
    assert all(r.state.is_completed() for r in runs)
    report = json.loads((root.reports / "rq2-test" / "rq2.json").read_text())
    assert report[SCENARIO]["evoeye"][0]["campaign_id"] == res["evoeye"][0]["campaign_id"]
    md = (root.reports / "rq2-test" / "rq2.md").read_text()
    assert "| evoeye |" in md and "| aem-evo |" in md and "| AEM (AEM-Evo's G_0) |" in md
    assert res["aem-evo"][0]["rounds"][-1]["version"].startswith("aem-")
    # the control: G_0's recipe on D_init with another seed, assessed like every G_r
    (control,) = res["reseeded"]
    assert control["version"] not in (g0, res["evoeye"][0]["rounds"][-1]["version"])
    assert "| G_0 re-seeded ×1 (no new data) |" in (root.reports / "rq2-test" / "rq2.md"
                                                    ).read_text()
    assert initial_monitor(root, SCENARIO) == g0  # a control never becomes G_0
    # re-running resumes: same campaigns, nothing simulated twice, the control reused
    versions = list_versions(root)
    again = experiment_flow(params)
    assert again["results"][SCENARIO]["evoeye"][0]["rounds"] == res["evoeye"][0]["rounds"]
    assert again["results"][SCENARIO]["reseeded"] == res["reseeded"]
    assert list_versions(root) == versions


def test_a_failed_campaign_stops_the_flows_other_campaigns(prefect_server, fresh_root) -> None:
    from evoeye.evolve.campaign.guard import CampaignBusyError, campaign_lease

    root, g0 = fresh_root
    params = ExperimentParams(root=str(root.path), scenarios=[SCENARIO],
                              strategies=["uniform", "evoeye"], repetitions=1, budget_s=600.0,
                              controls=0, workers=2, n_round=1, epochs=1, split_seed=0,
                              train_frac=0.5, val_frac=0.25)
    plan = plan_experiment(root, [SCENARIO], params.base(), strategies=params.strategies,
                           seeds=[0], budget_s=600.0)
    busy, other = Campaign(root, plan[1]), Campaign(root, plan[0])
    with campaign_lease(root, busy.campaign_id), pytest.raises(CampaignBusyError):
        experiment_flow(params)  # the evoeye campaign is "already running" elsewhere
    with campaign_lease(root, other.campaign_id):
        pass  # the uniform campaign stopped with the flow
    assert not other.finished()
    assert not list((root.warehouse / ".locks").glob("stop-*"))  # the request is withdrawn
