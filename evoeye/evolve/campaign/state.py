"""A campaign's state between rounds: D_init, D_r with its outcomes, G_r, and the run seeds."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from evoeye.evolve.campaign.config import REPLAY_RATIO, CampaignConfig
from evoeye.evolve.search.fitness import criticality
from evoeye.evolve.search.protocol import Strategy
from evoeye.evolve.search.records import Records
from evoeye.log import read_run
from evoeye.paths import DataRoot
from evoeye.seeds import campaign_run_seed
from evoeye.sim.episode import RunSpec
from evoeye.sim.runner import run_spec
from evoeye.store import Warehouse
from evoeye.store.feedback import RoundRow
from evoeye.store.selection import SplitSpec


class NoInitialDataError(LookupError):
    """A campaign needs the scenario's initial (round 0) runs in the warehouse."""


class MixedProfilesError(ValueError):
    """D_init holds runs of several ADS profiles: a campaign's regime is one profile."""


def read_initial(root: DataRoot, scenario: str, splits: SplitSpec) -> dict[str, np.ndarray]:
    """D_init: the train split of the scenario's round-0 runs, columns by name (a warehouse
    query; the same for every campaign of the scenario and split)."""
    t = Warehouse(root).query("initial_records", scenario=scenario, **asdict(splits)).to_pydict()
    if not t["scenario_id"]:
        raise NoInitialDataError(f"no initial (round 0) training runs of {scenario!r} in "
                                 f"{root.warehouse}: simulate and ingest them first")
    profiles = sorted(set(t["ads_profile"]))
    if len(profiles) > 1:
        raise MixedProfilesError(f"the initial runs of {scenario!r} in {root.warehouse} were "
                                 f"driven by several ADS profiles ({', '.join(profiles)}): a "
                                 "campaign acquires runs of one regime; keep each profile's "
                                 "runs in a data root of its own")
    return {k: np.asarray(v, dtype=object if k in ("scenario_id", "ads_profile") else None)
            for k, v in t.items()}


def initial_profile(initial: dict[str, np.ndarray]) -> str:
    """The ADS profile of D_init's runs (`read_initial` checks there is one): the campaign
    acquires its runs under it too."""
    return str(initial["ads_profile"][0])


@dataclass
class CampaignState:
    """D_r and G_r after `round` finished rounds, with the strategy that acquired D_r \\ D_init."""

    campaign_id: str
    round: int
    monitor: str
    records: Records
    ok: np.ndarray  # (n,) bool: the run finished and can train the monitor
    n_init: int
    strategy: Strategy
    rounds: list[RoundRow]
    # this round's proposals whose run the root already held: (that run's id, its batch)
    redrawn: list[tuple[str, str]] = field(default_factory=list)

    @property
    def spent_s(self) -> float:
        return float(self.records.tail(self.n_init).duration_s.sum())

    @property
    def acquired(self) -> int:
        return self.records.n - self.n_init

    def training_runs(self, update: str, seed: int) -> list[str]:
        """The runs of D_r the monitor update trains on: every ok record, or with `update`
        "replay" the round's new ok runs after a sample of as many earlier ones (seeded by the
        campaign `seed` and the round); none when the round has no ok run, or when no ok run of
        D_r collided (one class, nothing to learn: G_r stays)."""
        ok = self.records.scenario_id[self.ok]
        if not self.records.collided[self.ok].any():
            return []
        seen = {*self.records.scenario_id[:self.n_init],
                *(s for r in self.rounds for s in r.scenario_ids)}
        is_new = np.array([s not in seen for s in ok], dtype=bool)
        new, earlier = ok[is_new], ok[~is_new]
        if len(new) == 0:
            return []
        if update != "replay":
            return [str(s) for s in ok]
        rng = np.random.default_rng([seed, self.round + 1])
        k = min(len(earlier), int(round(REPLAY_RATIO * len(new))))
        pick = np.sort(rng.choice(len(earlier), size=k, replace=False))
        collided = self.records.collided[self.ok]
        if not collided[pick].any() and not collided[is_new].any() and collided[~is_new].any():
            pick[0:1] = rng.choice(np.flatnonzero(collided[~is_new]), size=1)  # both classes
        return [str(s) for s in (*earlier[np.sort(pick)], *new)]


def run_seed(campaign_seed: int, k: int) -> int:
    """The simulation seed of proposal k (0-based) of an efficiency curve's generative
    acquisition: the stream campaigns drew from before `evoeye.seeds` (`[seed, k]`, which meets
    a batch's at k = 0), kept so that the stored curves' runs keep their ids."""
    return int(np.random.SeedSequence([campaign_seed, k]).generate_state(1)[0])


MAX_REDRAWS = 100  # run seeds tried past the first for a proposal whose run the root holds


def held_runs(root: DataRoot, scenario: str, campaign_id: str,
              records: Records) -> dict[str, str]:
    """scenario_id → batch of the campaign's records (D_init, its earlier rounds' runs) and of
    every round-0 run of `scenario` the root holds (batches, Test Sets). Other campaigns' runs
    are left out: they may be written while this one runs, and what it draws must not depend
    on that (each campaign's streams are its own: `evoeye.seeds`)."""
    rows = Warehouse(root).sql(
        "SELECT scenario_id, batch FROM scenarios WHERE logical_scenario = ? AND round = 0",
        [scenario]).to_pydict()
    return {**{str(s): campaign_id for s in records.scenario_id},
            **dict(zip(rows["scenario_id"], rows["batch"], strict=True))}


def fresh_spec(cfg: CampaignConfig, campaign_id: str, x: np.ndarray, state: CampaignState,
               held: dict[str, str], *, ads: str, number: int | None = None) -> RunSpec:
    """The run of proposal `x` (number `number` of the campaign, by default `state.acquired`:
    the next), its run seed redrawn while `held` has the run it gives; each such run is added
    to `state.redrawn`. Deterministic for the same root, so a resumed round redraws alike."""
    number = state.acquired if number is None else number
    for attempt in range(MAX_REDRAWS + 1):
        seed = campaign_run_seed(cfg.seed, campaign_id, number, attempt)
        spec = run_spec(cfg.scenario, x, seed, batch=campaign_id, source=cfg.strategy,
                        round=state.round + 1, ads=ads)
        if spec.scenario_id not in held:
            return spec
        state.redrawn.append((spec.scenario_id, held[spec.scenario_id]))
    raise RuntimeError(f"campaign {campaign_id}: proposal {number} gave "
                       f"{MAX_REDRAWS + 1} runs the data root already holds, the last "
                       f"{spec.scenario_id} of batch {held[spec.scenario_id]}")


def redrawn_note(state: CampaignState) -> str:
    """'' or what the round's report says of proposals whose run the root already held."""
    if not state.redrawn:
        return ""
    sid, batch = state.redrawn[0]
    more = f" and {len(state.redrawn) - 1} more" if len(state.redrawn) > 1 else ""
    return (f"{len(state.redrawn)} proposal(s) gave a run the root already holds ({sid} of "
            f"batch {batch}{more}): run seed redrawn, no run acquired twice")


def run_outcome(run: dict[str, Any]) -> dict[str, Any]:
    """Records columns of one run from its log metadata or its scenarios row (a failed run is
    not critical)."""
    collided = bool(run["collided"])
    gap = run.get("min_distance_m")
    return {
        "fitness": float(criticality(collided, np.nan if gap is None else float(gap))),
        "collided": collided, "duration_s": float(run["duration_s"]),
        "scenario_id": str(run["scenario_id"]),
    }


def acquired_runs(root: DataRoot, log_path: Callable[[str], Path],
                  ids: list[str]) -> list[dict[str, Any]]:
    """The outcome (params, collided, min_distance_m, duration_s, status) of acquired runs by
    id, from the warehouse; from its log's metadata (at `log_path(id)`) for a run not ingested."""
    found = {r["scenario_id"]: r for r in (Warehouse(root).query(
        "campaign_records", ids=ids).to_pylist() if ids else [])}
    return [found.get(sid) or read_run(log_path(sid), topics=()).metadata for sid in ids]


def records_of(initial: dict[str, np.ndarray],
               acquired: Iterable[dict[str, Any]]) -> tuple[Records, np.ndarray]:
    """(D_r without feedback, (n,) bool ok) of D_init (`Campaign.initial`) and the acquired runs
    (each with params, the outcome and status), in order."""
    records = Records(
        params=np.stack([np.asarray(p, float) for p in initial["params"]]),
        feedback=np.full(len(initial["scenario_id"]), np.nan),
        fitness=criticality(initial["collided"].astype(bool),
                            np.array(initial["min_distance_m"], dtype=float)),
        collided=initial["collided"].astype(bool),
        duration_s=initial["duration_s"].astype(float), scenario_id=initial["scenario_id"],
    )
    ok = [True] * records.n
    for run in acquired:
        records = records.append(np.asarray(run["params"], float), **run_outcome(run))
        ok.append(run["status"] == "ok")
    return records, np.array(ok, bool)
