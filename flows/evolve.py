"""Flow: an evolution campaign; every acquisition round is its own (sub)flow run.

Each flow run is named after its campaign (`evolve-<scenario>-<strategy>-s<seed>`, its rounds
`round-<r>-…`) and publishes the campaign's rounds, with each monitor's figures where
assessed, as a Markdown artifact. A round flow run runs propose → simulate → score → ingest
(task `acquire`, which ingests its runs from the conversion it scored them with), `ingest` (any
of the campaign's logs an interrupted `acquire` left out, and the DuckDB catalog file), `train`
and `score` (feedback refresh and the round's commit). The tasks pass only the parameters and
run ids: each rebuilds the campaign's state from the data root (`Campaign.start`, with the
round's new run ids), where `acquire` left the new logs and their feedback. Because the state
lives in the warehouse, a round flow run that crashed is simply run again by the next flow run
(e.g. tomorrow night's), with nothing lost or repeated. A flow run that adds no round, its
budget spent, says so in its log and its result (`nothing_to_do`, `message`).
"""

from __future__ import annotations

from functools import cache
from typing import Any

from prefect import flow, get_run_logger, task
from prefect.cache_policies import NONE
from pydantic import Field, model_validator

from evoeye.evolve.campaign.config import CampaignConfig, config_from, option_values
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.report import rounds_markdown
from evoeye.evolve.campaign.state import CampaignState, redrawn_note
from evoeye.paths import DataRoot
from evoeye.store.feedback import read_rounds
from flows.campaign_params import KnownNames, campaign_model
from flows.published import named, publish


class CampaignRun(KnownNames):
    """One campaign (its id follows from the options, minus the budget and max_rounds)."""

    root: str | None = Field(None, description="Data root; None: $EVOEYE_HOME, else "
                             "./evoeye-data.")
    max_rounds: int | None = Field(None, ge=1, description="Rounds in this flow run; None: "
                                   "until the budget is spent.")
    assess: bool = Field(False, description="Also score every G_r on the Test Set and the "
                         "Hard Set.")

    def config(self) -> CampaignConfig:
        return config_from(self.model_dump())

    @model_validator(mode="after")
    def _some_budget(self) -> CampaignRun:
        if getattr(self, "budget_s", 1.0) <= 0:
            raise ValueError("budget_s must be greater than 0: no run fits in no simulated time")
        return self

    def run_name(self) -> str:
        return f"evolve-{self.scenario}-{self.strategy}-s{self.seed}"

    @classmethod
    def of(cls, config: CampaignConfig, root: str | None = None, **options: Any) -> CampaignRun:
        """The parameters of the campaign `config` (ValueError if it sets an internal field
        no option carries: the flow would run a different campaign)."""
        return cls(root=root, **option_values(config), **options)


EvolveParams = campaign_model("EvolveParams", CampaignRun, __name__)


def make_campaign(params: CampaignRun) -> Campaign:
    """The campaign of `params`; with `assess`, every G_r it stores is assessed on the Test Set
    and the Hard Set (the assessor is built on first use: it loads and scores the Test Set)."""
    cfg, root = params.config(), DataRoot.resolve(params.root)
    if not params.assess:
        return Campaign(root, cfg)
    from evoeye.evolve.campaign.assess import Assessor

    assessor = cache(lambda: Assessor.of(Campaign(root, cfg)))
    return Campaign(root, cfg, assess=lambda version: assessor()(version))


@task(cache_policy=NONE)
def acquire(params: CampaignRun) -> list[str]:
    """Propose → simulate → feedback under G_r, N_round times (or until the budget is spent)."""
    campaign = make_campaign(params)
    state = campaign.start()
    new_ids = campaign.acquire(state)
    if note := redrawn_note(state):
        get_run_logger().warning(note)
    return new_ids


@task(cache_policy=NONE, retries=1, retry_delay_seconds=2)
def ingest_round(params: CampaignRun) -> int:
    """The campaign's logs `acquire` did not ingest (none unless it was interrupted), and the
    DuckDB catalog file's views (idempotent)."""
    return len(make_campaign(params).ingest().ingested)


@task(cache_policy=NONE)
def train(params: CampaignRun, new_ids: list[str]) -> tuple[str, float]:
    """G_{r+1} from G_r on D_r (the stored records and the round's new runs); (version, s)."""
    campaign = make_campaign(params)
    return campaign.update_monitor(campaign.start(new_ids))


@task(cache_policy=NONE)
def score(params: CampaignRun, new_ids: list[str], version: str,
          train_s: float) -> dict[str, Any]:
    """Refresh every record's feedback with G_{r+1} and commit the round."""
    campaign = make_campaign(params)
    row = campaign.finish_round(campaign.start(new_ids), new_ids, version, train_s)
    return {"round": row.round, "monitor": row.monitor_version, "records": row.n_records,
            "simulated_s": row.simulated_s,
            "metrics": row.metrics.as_dict() if row.metrics else None}


def publish_rounds(campaign: Campaign, key: str) -> None:
    """The campaign's rounds so far (with G_r's figures where assessed) as artifact `key`."""
    publish(key, rounds_markdown(read_rounds(campaign.root, campaign.campaign_id)),
            f"campaign {campaign.campaign_id}")


@flow(name="evoeye-evolve-round", log_prints=True)
def round_flow(params: EvolveParams) -> dict[str, Any] | None:
    """One acquisition round of the campaign `params` names, from its stored state."""
    logger = get_run_logger()
    new_ids = acquire(params)
    if not new_ids:
        logger.info("budget spent: no run fits in the %.1f s budget", params.budget_s)
        return None
    ingest_round(params)
    version, train_s = train(params, new_ids)
    out = score(params, new_ids, version, train_s)
    logger.info("round %d: %d new runs, monitor %s, %.1f / %.1f s simulated", out["round"],
                len(new_ids), version, out["simulated_s"], params.budget_s)
    publish_rounds(make_campaign(params), "evoeye-evolve-round")
    return out


def nothing_to_do(campaign: Campaign, state: CampaignState) -> str:
    """What a flow run that added no round says: the campaign has spent its budget."""
    cfg = campaign.config
    return (f"nothing to do: campaign {campaign.campaign_id} has spent its budget "
            f"({state.spent_s:.0f} of {cfg.budget_s:.0f} simulated s; a run may last "
            f"{cfg.max_run_s:.0f} s); a larger budget_s continues it")


def run_campaign(params: CampaignRun) -> dict[str, Any]:
    """The body of a campaign flow run: rounds (each a `round-<r>` flow run) until the budget
    is spent or max_rounds; a run that adds none says so in its log and its result."""
    logger = get_run_logger()
    campaign = make_campaign(params)
    state = campaign.start()
    rounds: list[dict[str, Any]] = []
    while not campaign.done(state) and (params.max_rounds is None
                                        or len(rounds) < params.max_rounds):
        name = f"round-{state.round + 1}-{params.scenario}-{params.strategy}-s{params.seed}"
        out = round_flow.with_options(flow_run_name=name)(params)
        if out is None:
            break
        rounds.append(out)
        state = campaign.start()
    idle = None if rounds else nothing_to_do(campaign, state)
    if idle:
        logger.warning(idle)
    publish_rounds(campaign, "evoeye-evolve")
    return {"campaign_id": campaign.campaign_id, "rounds": rounds, "round": state.round,
            "monitor": state.monitor, "simulated_s": state.spent_s,
            "done": campaign.done(state), "root": str(campaign.root.path),
            "nothing_to_do": idle is not None,
            "message": idle or f"{len(rounds)} round(s) added, now at round {state.round}"}


@flow(name="evoeye-evolve", log_prints=True,
      flow_run_name=named(lambda p: (p or EvolveParams()).run_name()))
def evolution_flow(params: EvolveParams | None = None) -> dict[str, Any]:
    """Run rounds (each a `round-<r>` flow run) until the budget is spent or max_rounds."""
    return run_campaign(params or EvolveParams())


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(EvolveParams, evolution_flow, __doc__)
