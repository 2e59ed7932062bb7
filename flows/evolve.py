"""Flow: an evolution campaign; every acquisition round is its own (sub)flow run `round-<r>`.

A round flow run rebuilds the campaign state from the data root (`Campaign.start`), then runs
propose → simulate (task `acquire`), `ingest`, `train` and `score` (feedback refresh and the
round's commit). Because the state lives in the warehouse, a round flow run that crashed is
simply run again by the next flow run (e.g. tomorrow night's), with nothing lost or repeated.
"""

from __future__ import annotations

from typing import Any

from prefect import flow, get_run_logger, task
from prefect.cache_policies import NONE
from pydantic import BaseModel, Field, ValidationInfo, field_validator

from evoeye.evolve.campaign.config import UPDATE_MODES, CampaignConfig
from evoeye.evolve.campaign.experiment import methods
from evoeye.evolve.campaign.loop import Campaign, CampaignState
from evoeye.evolve.campaign.scoring import FEEDBACK_MODES
from evoeye.evolve.search.strategies import STRATEGIES
from evoeye.monitor.families import evolvable_families
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from evoeye.store import SplitSpec

KNOWN = {"scenario": lambda: SCENARIOS, "strategy": lambda: STRATEGIES,
         "update": lambda: UPDATE_MODES, "feedback": lambda: FEEDBACK_MODES,
         "family": evolvable_families, "method": methods}  # the names a parameter may take


def check_known(kind: str, values: list[str]) -> None:
    """ValueError naming the values of `kind` (a KNOWN key) that are unknown, or no value."""
    known = KNOWN[kind]()
    unknown = [v for v in values if v not in known]
    if unknown or not values:
        raise ValueError(f"unknown {kind} {unknown}; known: {sorted(known)}")


class EvolveParams(BaseModel):
    """One campaign (its id follows from these, minus the budget and max_rounds)."""

    root: str | None = None  # default: $EVOEYE_HOME or ./evoeye-data
    scenario: str = Field("highway-cut-in", json_schema_extra={"enum": sorted(SCENARIOS)})
    strategy: str = Field("evoeye", json_schema_extra={"enum": sorted(STRATEGIES)})
    budget_s: float = Field(600.0, ge=0.0)  # simulated seconds for the whole campaign
    seed: int = Field(0, ge=0)
    monitor: str | None = None  # G_0; default: the newest from-scratch monitor of the scenario
    n_round: int = Field(20, ge=1)
    update: str = Field("finetune", json_schema_extra={"enum": list(UPDATE_MODES)})
    feedback: str = Field("raw", json_schema_extra={"enum": list(FEEDBACK_MODES)})
    family: str = Field("fusion", json_schema_extra={"enum": evolvable_families()})
    reference: str | None = None  # aem: the FusionMonitor G_0 whose Hard Set judges
    epochs: int | None = Field(None, ge=1)
    max_rounds: int | None = Field(None, ge=1)  # rounds in this flow run (None: to the budget)
    split_seed: int = 0
    train_frac: float = Field(0.5, ge=0.0, le=1.0)
    val_frac: float = Field(0.125, ge=0.0, le=1.0)
    assess: bool = False  # also score every G_r on the Test Set and the Hard Set

    @field_validator("scenario", "strategy", "update", "feedback", "family")
    @classmethod
    def _known(cls, value: str, info: ValidationInfo) -> str:
        check_known(info.field_name, [value])
        return value

    @classmethod
    def of(cls, config: CampaignConfig, root: str | None = None, **options: Any) -> EvolveParams:
        """The parameters of the campaign `config` (fields EvolveParams does not carry must be
        at their defaults, or the flow would run a different campaign)."""
        default = CampaignConfig(config.scenario)
        for name in ("delta", "horizon_s", "patience", "max_run_s"):
            if getattr(config, name) != getattr(default, name):
                raise ValueError(f"the evolution flow runs campaigns with the default {name}")
        return cls(root=root, scenario=config.scenario, strategy=config.strategy,
                   budget_s=config.budget_s, seed=config.seed, monitor=config.monitor,
                   n_round=config.n_round, update=config.update, epochs=config.epochs,
                   feedback=config.feedback, family=config.family, reference=config.reference,
                   split_seed=config.splits.seed, train_frac=config.splits.train_frac,
                   val_frac=config.splits.val_frac, **options)

    def config(self) -> CampaignConfig:
        return CampaignConfig(
            scenario=self.scenario, strategy=self.strategy, budget_s=self.budget_s,
            seed=self.seed, monitor=self.monitor, n_round=self.n_round, update=self.update,
            epochs=self.epochs, feedback=self.feedback, family=self.family,
            reference=self.reference,
            splits=SplitSpec(self.split_seed, self.train_frac, self.val_frac),
        )


def make_campaign(params: EvolveParams) -> Campaign:
    cfg = params.config()
    root = DataRoot.resolve(params.root)
    assess = None
    if params.assess:
        from evoeye.evolve.campaign.assess import Assessor

        assess = Assessor.of(Campaign(root, cfg))
    return Campaign(root, cfg, assess=assess)


@task(cache_policy=NONE)
def acquire(campaign: Campaign, state: CampaignState) -> list[str]:
    """Propose → simulate → feedback under G_r, N_round times (or until the budget is spent)."""
    return campaign.acquire(state)


@task(cache_policy=NONE, retries=1, retry_delay_seconds=2)
def ingest_round(campaign: Campaign) -> int:
    """The round's logs into the warehouse (idempotent)."""
    return len(campaign.ingest().ingested)


@task(cache_policy=NONE)
def train(campaign: Campaign, state: CampaignState) -> tuple[str, float]:
    """G_{r+1} from G_r on D_r; (version, wall seconds)."""
    return campaign.update_monitor(state)


@task(cache_policy=NONE)
def score(campaign: Campaign, state: CampaignState, new_ids: list[str], version: str,
          train_s: float) -> dict[str, Any]:
    """Refresh every record's feedback with G_{r+1} and commit the round."""
    row = campaign.finish_round(state, new_ids, version, train_s)
    return {"round": row.round, "monitor": row.monitor_version, "records": row.n_records,
            "simulated_s": row.simulated_s, "metrics": row.metrics}


@flow(name="evoeye-evolve-round", log_prints=True)
def round_flow(params: EvolveParams) -> dict[str, Any] | None:
    """One acquisition round of the campaign `params` names, from its stored state."""
    logger = get_run_logger()
    campaign = make_campaign(params)
    state = campaign.start()
    new_ids = acquire(campaign, state)
    if not new_ids:
        logger.info("budget spent: %.1f of %.1f s", state.spent_s, params.budget_s)
        return None
    ingest_round(campaign)
    version, train_s = train(campaign, state)
    out = score(campaign, state, new_ids, version, train_s)
    logger.info("round %d: %d new runs, monitor %s, %.1f / %.1f s simulated", out["round"],
                len(new_ids), version, out["simulated_s"], params.budget_s)
    return out


@flow(name="evoeye-evolve", log_prints=True)
def evolution_flow(params: EvolveParams | None = None) -> dict[str, Any]:
    """Run rounds (each a `round-<r>` flow run) until the budget is spent or max_rounds."""
    params = params or EvolveParams()
    campaign = make_campaign(params)
    state = campaign.start()
    rounds: list[dict[str, Any]] = []
    while not campaign.done(state) and (params.max_rounds is None
                                        or len(rounds) < params.max_rounds):
        name = f"round-{state.round + 1}"
        out = round_flow.with_options(flow_run_name=name)(params)
        if out is None:
            break
        rounds.append(out)
        state = campaign.start()
    return {"campaign_id": campaign.campaign_id, "rounds": rounds, "round": state.round,
            "monitor": state.monitor, "simulated_s": state.spent_s,
            "done": campaign.done(state), "root": str(campaign.root.path)}


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(EvolveParams, evolution_flow, __doc__)
