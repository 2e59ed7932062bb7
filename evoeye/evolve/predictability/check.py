"""The predictability check of one regime on a data root: its runs, a monitor's error, re-runs.

A regime is a logical scenario and an ADS profile; its runs are read from the warehouse (one
batch, or all), each re-simulation uses the run's own profile. The monitor's error is measured
only on runs it did not train on: runs ingested after it was created, and — when its card
records its train and validation runs as a filter — the runs outside both.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from datetime import datetime
from typing import Any

import numpy as np

from evoeye.evolve.campaign.scoring import warehouse_feedback
from evoeye.evolve.predictability import metrics
from evoeye.evolve.search.boundary import signed_margin_m
from evoeye.evolve.search.fitness import criticality
from evoeye.evolve.search.records import Records
from evoeye.monitor.families import initial_monitor, load_calibrated
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.store import Warehouse

NOISE_SEED = 7919  # re-simulation j of sampled θ i runs with seed SeedSequence([7919, seed, i, j])

# (scenario, x in parameter units, run seed, ADS profile) → 1.0 collided, 0.0 not, NaN failed
Simulate = Callable[[str, np.ndarray, int, str], float]


class RegimeError(LookupError):
    """No runs to check, or runs of several ADS profiles where one regime was meant."""


@dataclass(frozen=True)
class RegimeRuns:
    """The finished runs of one regime: θ, outcome, margin, when each was ingested."""

    scenario: str
    ads_profile: str
    batch: str | None
    scenario_id: np.ndarray  # (n,) str
    params: np.ndarray  # (n, dim) parameter units
    collided: np.ndarray  # (n,) bool
    margin_m: np.ndarray  # (n,) signed margin (`evoeye.evolve.search.boundary`)
    ingested_at: np.ndarray  # (n,) datetime

    @property
    def u(self) -> np.ndarray:
        return get_scenario(self.scenario).normalise(self.params)


def regime_runs(root: DataRoot, scenario: str, batch: str | None = None,
                ads: str | None = None) -> RegimeRuns:
    """The runs of `scenario` (of `batch`, under profile `ads`; None: any) — RegimeError if
    there are none, or if they were driven by several profiles."""
    t = Warehouse(root).query("predictability_runs", scenario=scenario, batch=batch,
                              ads=ads).to_pydict()
    where = f"{scenario!r}" + (f", batch {batch!r}" if batch else "") + (
        f", ADS profile {ads!r}" if ads else "")
    if not t["scenario_id"]:
        raise RegimeError(f"no finished runs of {where} in {root.warehouse}")
    profiles = sorted(set(t["ads_profile"]))
    if len(profiles) > 1:
        raise RegimeError(f"the runs of {where} were driven by several ADS profiles "
                          f"({', '.join(profiles)}): pick one regime with --ads")
    params = np.array(t["params"], dtype=float)
    collided = np.array(t["collided"], dtype=bool)
    gap_m = np.array([np.nan if g is None else g for g in t["min_distance_m"]], dtype=float)
    margin = signed_margin_m(Records(params, np.full(len(params), np.nan),
                                     fitness=criticality(collided, gap_m), collided=collided))
    return RegimeRuns(scenario, profiles[0], batch, np.array(t["scenario_id"], dtype=object),
                      params, collided, margin, np.array(t["ingested_at"], dtype=object))


def unseen(root: DataRoot, card: dict[str, Any], runs: RegimeRuns) -> np.ndarray:
    """(n,) bool: the runs the monitor of `card` did not train or early-stop on."""
    created = datetime.fromisoformat(card["created_at"])
    later = np.array([t > created for t in runs.ingested_at], dtype=bool)
    selections = [card.get("selection", {}).get(k, {}) for k in ("train", "val")]
    if not all(s.get("kind") == "filter" for s in selections):
        return later  # an explicit run list or SQL: only the ingestion time tells
    warehouse = Warehouse(root)
    seen = {s for sel in selections
            for s in warehouse.query("select_runs", **sel["params"]).column(0).to_pylist()}
    return later | ~np.isin(runs.scenario_id, list(seen))


def monitor_error(root: DataRoot, runs: RegimeRuns, version: str,
                  feedback: str = "raw") -> tuple[np.ndarray, np.ndarray]:
    """(mask (n,) of the runs the monitor did not see, their error (n,), NaN elsewhere): the
    per-run feedback mean |ŷ − y| under `version`, ŷ as the feedback mode takes it."""
    monitor = load_calibrated(root, version)
    mask = unseen(root, monitor.card, runs)
    error = np.full(len(runs.scenario_id), np.nan)
    if mask.any():
        ids = runs.scenario_id[mask]
        fb = warehouse_feedback(root, monitor, list(ids), monitor.card.get("horizon_s", 3.0),
                                feedback)
        error[mask] = fb.aligned(ids)
    return mask, error


def simulate_collided(scenario: str, x: np.ndarray, seed: int, profile: str) -> float:
    """Whether the run (scenario, x, seed) under ADS `profile` collides (NaN if it failed)."""
    from evoeye.sim.runner import run_episode, run_spec

    episode = run_episode(run_spec(scenario, x, seed, ads=profile))
    return np.nan if episode.outcome.status != "ok" else float(episode.outcome.collided)


def uniform_pick(n: int, sample: int, seed: int) -> np.ndarray:
    """`sample` of n runs drawn uniformly (seeded), ascending."""
    return np.sort(np.random.default_rng(seed).choice(n, min(sample, n), replace=False))


def boundary_pick(p_collision: np.ndarray, sample: int) -> np.ndarray:
    """The `sample` runs whose out-of-fold collision probability is nearest ½: the θ where
    the outcome is least predictable, where boundary-seeking samples (ascending)."""
    return np.sort(np.argsort(np.abs(p_collision - 0.5), kind="stable")[:sample])


def label_noise(runs: RegimeRuns, pick: np.ndarray, seeds: int, seed: int = 0,
                workers: int = 1, simulate: Simulate = simulate_collided) -> metrics.Flips:
    """The runs `pick` (indices), each re-simulated under `seeds` new seeds with its own ADS
    profile: how often the outcome flips."""
    jobs = [(runs.scenario, runs.params[i], _noise_seed(seed, i, j), runs.ads_profile)
            for i in pick for j in range(seeds)]
    if workers > 1:
        with ProcessPoolExecutor(workers) as pool:
            outcomes = list(pool.map(simulate, *zip(*jobs, strict=True), chunksize=4))
    else:
        outcomes = [simulate(*job) for job in jobs]
    return metrics.flips(runs.collided[pick], np.reshape(outcomes, (len(pick), seeds)))


def _noise_seed(seed: int, i: int, j: int) -> int:
    return int(np.random.SeedSequence([NOISE_SEED, seed, int(i), j]).generate_state(1)[0])


def check_regime(root: DataRoot, scenario: str, *, batch: str | None = None,
                 ads: str | None = None, monitor: str | None = None, feedback: str = "raw",
                 sample: int = 30, seeds: int = 4, seed: int = 0, workers: int = 1,
                 simulate: Simulate = simulate_collided) -> dict[str, Any]:
    """Every figure of one regime, as a JSON-able dict (`sample` or `seeds` 0: no re-runs;
    `monitor` None: the scenario's initial monitor, if there is one). The label noise is
    measured twice: on `sample` θ drawn uniformly, and on the `sample` θ nearest the failure
    boundary (`boundary_pick`)."""
    from evoeye.monitor.families import NoMonitorError

    runs = regime_runs(root, scenario, batch, ads)
    p_collision = metrics.cv_probabilities(runs.u, runs.collided, seed)
    collision = metrics.classified(runs.collided, p_collision)
    margin = metrics.cv_regression(runs.u, runs.margin_m, seed)
    error, version, n_unseen, note = None, monitor, 0, None
    try:
        version = monitor or initial_monitor(root, scenario)
    except NoMonitorError as e:
        note = str(e)
    if version is not None:
        mask, per_run = monitor_error(root, runs, version, feedback)
        n_unseen = int(mask.sum())
        error = metrics.cv_regression(runs.u[mask], per_run[mask], seed) if n_unseen else None
    noise = boundary = None
    if sample and seeds:
        noise = label_noise(runs, uniform_pick(len(runs.params), sample, seed), seeds, seed,
                            workers, simulate)
        if p_collision is not None:
            boundary = label_noise(runs, boundary_pick(p_collision, sample), seeds, seed,
                                   workers, simulate)
    return {
        "scenario": scenario, "ads_profile": runs.ads_profile, "batch": batch,
        "runs": len(runs.scenario_id), "collision_share": float(runs.collided.mean()),
        "collision": metrics.as_dict(collision), "margin": metrics.as_dict(margin),
        "monitor": {"version": version, "feedback": feedback, "unseen_runs": n_unseen,
                    "error": metrics.as_dict(error), "note": note},
        "label_noise": metrics.as_dict(noise),
        "boundary_noise": metrics.as_dict(boundary),
        "verdict": metrics.verdict(collision, error, noise, boundary),
    }
