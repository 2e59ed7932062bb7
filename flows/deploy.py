"""Deployment: the evolution flow every night on a cron schedule, with pydantic parameters.

Serve it (a long-running process that polls the Prefect API and runs the scheduled flow runs):

    prefect server start                        # terminal 1: the API and UI on :4200
    python -m flows.deploy --scenario highway-cut-in --strategy evoeye --budget-s 21600
                                                # terminal 2: registers and serves the deployment

Each night's flow run resumes the same campaign (its id follows from the parameters), runs
`rounds_per_night` rounds and stops; when the budget is spent the runs return at once. Without
`--strategy` it runs the default strategy, `DEFAULT_STRATEGY` of
`evoeye.evolve.campaign.config` (the same constant `evoeye evolve` defaults to).
"""

from __future__ import annotations

from prefect.client.schemas.objects import ConcurrencyLimitConfig, ConcurrencyLimitStrategy
from prefect.deployments.runner import RunnerDeployment
from prefect.schedules import Cron

from flows.evolve import EvolveParams, evolution_flow

DEPLOYMENT_NAME = "nightly-evolution"
NIGHTLY_CRON = "0 2 * * *"  # 02:00 every day
TIMEZONE = "UTC"
NIGHTLY_BUDGET_S = 21_600.0  # the whole campaign's simulated seconds, unless --budget-s


def nightly_deployment(params: EvolveParams | None = None, *, cron: str = NIGHTLY_CRON,
                       name: str = DEPLOYMENT_NAME, timezone: str = TIMEZONE) -> RunnerDeployment:
    """The deployment object (nothing is registered until it is served or applied)."""
    params = params or EvolveParams()
    return evolution_flow.to_deployment(
        name=name,
        schedule=Cron(cron, timezone=timezone),
        parameters={"params": params.model_dump()},
        tags=["evoeye", "evolution", params.scenario, params.strategy],
        description="Nightly monitor-guided acquisition rounds (resumes the same campaign).",
        # one campaign must never run twice at once: its rounds share one warehouse writer
        concurrency_limit=ConcurrencyLimitConfig(
            limit=1, collision_strategy=ConcurrencyLimitStrategy.CANCEL_NEW),
    )


def main(argv: list[str] | None = None) -> None:
    """Serve the nightly deployment against the configured Prefect API ($PREFECT_API_URL)."""
    from prefect import serve

    from flows.command_line import parser_for

    ap = parser_for(EvolveParams, __doc__.splitlines()[0])
    ap.add_argument("--rounds-per-night", dest="max_rounds", type=int)
    ap.add_argument("--cron", default=NIGHTLY_CRON)
    given = vars(ap.parse_args(argv))
    cron = given.pop("cron")
    params = EvolveParams(**{"budget_s": NIGHTLY_BUDGET_S, "assess": True, **given})
    serve(nightly_deployment(params, cron=cron))


if __name__ == "__main__":
    main()
