"""Deployment: the evolution flow every night on a cron schedule, one parameter per field.

Serve it (a long-running process that polls the Prefect API and runs the scheduled flow runs):

    prefect server start                        # terminal 1: the API and UI on :4200
    python -m flows.deploy --scenario highway-cut-in --strategy evoeye --budget-s 21600
                                                # terminal 2: registers and serves the deployment

Each night's flow run resumes the same campaign (its id follows from the parameters), runs
`--max-rounds` rounds (NIGHTLY_ROUNDS unless given) and stops; once the budget is spent a run
says that it has nothing to do. The deployment's parameters are EvolveParams' fields, each its
own, so a flow run may override one and keep the others (`--param budget_s=800`). On start,
the runs of the deployment that a stopped serve process left Running or Pending are marked
Crashed, which frees the deployment's concurrency slot. Without `--strategy` it runs the
default strategy, `DEFAULT_STRATEGY` of `evoeye.evolve.campaign.config`.
"""

from __future__ import annotations

import fcntl
import hashlib
from pathlib import Path
from typing import IO, Any

from prefect import flow
from prefect.client.schemas.objects import ConcurrencyLimitConfig, ConcurrencyLimitStrategy
from prefect.deployments.runner import RunnerDeployment
from prefect.logging import get_logger
from prefect.schedules import Cron

from flows.api import configured_api_url
from flows.campaign_params import flat_parameters
from flows.command_line import Override
from flows.evolve import EvolveParams, run_campaign

DEPLOYMENT_NAME = "nightly-evolution"
NIGHTLY_CRON = "0 2 * * *"  # 02:00 every day
TIMEZONE = "UTC"
NIGHTLY_BUDGET_S = 21_600.0  # the whole campaign's simulated seconds, unless --budget-s
# rounds per night: at most 5 × N_round runs (≤ 20 s each: 2 000 simulated s with N_round 20)
# and 5 monitor updates, so the default budget lasts 11 nights or more, not one
NIGHTLY_ROUNDS = 5
LEFT_STATES = ("RUNNING", "PENDING")  # the states a dead serve process leaves its runs in
log = get_logger("flows.deploy")


def _night_name() -> str:
    from prefect.runtime import flow_run

    return EvolveParams.model_construct(**flow_run.parameters).run_name()


@flow(name="evoeye-evolve", log_prints=True, flow_run_name=_night_name)
@flat_parameters(EvolveParams)
def nightly_evolution(**fields: Any) -> dict[str, Any]:
    """The evolution flow with EvolveParams' fields as its parameters, each its own."""
    return run_campaign(EvolveParams(**fields))


def deployment_name(name: str = DEPLOYMENT_NAME) -> str:
    """`<flow>/<deployment>`, as `prefect deployment run` takes it."""
    return f"{nightly_evolution.name}/{name}"


def nightly_deployment(params: EvolveParams | None = None, *, cron: str = NIGHTLY_CRON,
                       name: str = DEPLOYMENT_NAME, timezone: str = TIMEZONE) -> RunnerDeployment:
    """The deployment object (nothing is registered until it is served or applied)."""
    params = params or EvolveParams()
    return nightly_evolution.to_deployment(
        name=name,
        schedule=Cron(cron, timezone=timezone),
        parameters=params.model_dump(),
        tags=["evoeye", "evolution", params.scenario, params.strategy],
        description="Nightly monitor-guided acquisition rounds (resumes the same campaign).",
        # one campaign must never run twice at once: its rounds share one warehouse writer
        concurrency_limit=ConcurrencyLimitConfig(
            limit=1, collision_strategy=ConcurrencyLimitStrategy.CANCEL_NEW),
    )


def crash_left_runs(name: str = DEPLOYMENT_NAME) -> list[str]:
    """Mark Crashed the flow runs of the deployment `name`, and their subflow runs, that are
    Running or Pending; their names. Only for a serve process starting, when no run of its
    deployment can be alive (`serve_lock`): a serve process that was killed left them so.
    Leaving Running or Pending releases the deployment's concurrency slot (Prefect's
    ReleaseFlowConcurrencySlots), which would otherwise stay taken until its lease expired
    and cancel a run started meanwhile."""
    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import (
        FlowRunFilter,
        FlowRunFilterDeploymentId,
        FlowRunFilterParentFlowRunId,
        FlowRunFilterState,
        FlowRunFilterStateType,
    )
    from prefect.client.schemas.objects import StateType
    from prefect.exceptions import ObjectNotFound
    from prefect.states import Crashed

    left = FlowRunFilterState(type=FlowRunFilterStateType(
        any_=[StateType[s] for s in LEFT_STATES]))
    with get_client(sync_client=True) as client:
        try:
            deployment = client.read_deployment_by_name(deployment_name(name))
        except ObjectNotFound:
            return []
        runs = client.read_flow_runs(flow_run_filter=FlowRunFilter(
            deployment_id=FlowRunFilterDeploymentId(any_=[deployment.id]), state=left))
        found, level = [], runs
        while level:  # and their subflow runs (a night's round), level by level
            found += level
            level = client.read_flow_runs(flow_run_filter=FlowRunFilter(
                parent_flow_run_id=FlowRunFilterParentFlowRunId(any_=[r.id for r in level]),
                state=left))
        for run in reversed(found):  # the rounds first, then their night
            client.set_flow_run_state(run.id, Crashed(
                message=f"its serve process stopped while it was {run.state_name}; marked "
                        "Crashed when serve started again"), force=True)
    names = [f"{r.name} ({r.state_name.lower()})" for r in found]
    if names:
        log.warning("a stopped serve process left %d flow run(s) of %s: marked Crashed, which "
                    "frees the deployment's concurrency slot: %s", len(names),
                    deployment_name(name), ", ".join(names))
    return names


def serve_lock(name: str = DEPLOYMENT_NAME) -> IO[str]:
    """An exclusive lock, held while the returned file is open, that no other process on this
    machine serves the deployment `name` of this Prefect API (RuntimeError if one does): only
    then are its Running runs the left-overs of a dead serve process."""
    from prefect.settings import PREFECT_API_URL, PREFECT_HOME

    api = hashlib.sha1(str(PREFECT_API_URL.value()).encode()).hexdigest()[:10]
    path = Path(PREFECT_HOME.value()) / f"evoeye-serve-{name}-{api}.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    held = path.open("a+")
    try:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        held.close()
        raise RuntimeError(f"another process serves {deployment_name(name)} on this machine "
                           f"(lock {path}): stop it first") from None
    return held


SERVER_NOTE = (
    "A schedule needs a running Prefect server (a temporary one has no scheduler): start "
    "`prefect server start` and set PREFECT_API_URL=http://127.0.0.1:4200/api.")
OVERRIDES = {
    "max_rounds": Override(help="Rounds per night: each scheduled flow run stops after them "
                           "(it resumes the campaign the next night).",
                           default=NIGHTLY_ROUNDS, aliases=("--rounds-per-night",)),
    "budget_s": Override(help="Simulated seconds the campaign's acquired runs may use in "
                         "total, over all nights.", default=NIGHTLY_BUDGET_S),
    "assess": Override(default=True),
}


def main(argv: list[str] | None = None) -> None:
    """Serve the nightly deployment against the configured Prefect API ($PREFECT_API_URL)."""
    from prefect import serve

    from flows.command_line import parser_for

    ap = parser_for(EvolveParams, __doc__.splitlines()[0], OVERRIDES)
    ap.add_argument("--cron", default=NIGHTLY_CRON,
                    help=f"When the flow runs, a cron expression in {TIMEZONE} (default: "
                         f"{NIGHTLY_CRON}).")
    ap.epilog = SERVER_NOTE
    given = vars(ap.parse_args(argv))
    cron = given.pop("cron")
    try:
        params = EvolveParams(**given)
        if not configured_api_url():
            raise RuntimeError(f"no Prefect server: {SERVER_NOTE}")
        lock = serve_lock()
    except (ValueError, RuntimeError) as exc:
        ap.error(str(exc))
    crash_left_runs()
    with lock:
        serve(nightly_deployment(params, cron=cron))


if __name__ == "__main__":
    main()
