"""A regime's data: its pool, validation, oracle and Test Sets, and its boundary set.

Each regime lives on a data root of its own (`regime_root`), so its warehouse holds one ADS
profile. The uniform sets are batches of `plan_uniform` with seeds of their own
(`EfficiencyConfig.data_seed` + 0 … 3); simulating resumes (logs on disk are kept) and ingest
adds only what is new.

The boundary set is built once, from no monitor: each colliding pool run (in a seeded order) is
paired with its nearest safe pool run in normalised θ, both ends are simulated again under one
run seed of the pair's own (a pair whose ends then do not bracket a collision is dropped: the
outcome flipped with the seed), and the segment between them is bisected `boundary_steps`
times under that seed, keeping the half whose ends differ. The set is the last safe and the last
colliding run of every pair: two runs of one seed, 1/2^steps of the pair's distance apart
across the failure boundary. Its ids are kept in `boundary.json` under the regime's root.

With `val_collisions` the validation set is enriched with collisions (`extend_validation`): the
validation batch's own stream (`plan_uniform` with its seed; a longer plan begins with the
shorter one) is drawn on past its `val_runs`, in chunks of `val_runs` runs (batch
`val-more-seed<its seed>`), until the further runs hold enough collisions; the first ones in
stream order are kept, so the set is the same whatever was simulated before (the further runs
are simulated for their outcome and only the colliding ones logged, chunk by chunk, resumably:
`stream.py`). Only the unsafe windows of those runs join the
validation set (`sets.RegimeData.load`): its negatives stay the
uniform batch's, so a threshold calibrated for a target false-positive rate is calibrated on the
same frames, while early stopping gets more positives, drawn from the same distribution (uniform
runs that collided). Whole colliding runs would not do: their frames before the horizon are
negatives too, and over-representing them would move the calibration. The kept ids are in
`val-collisions.json`.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from evoeye.atomic import atomic_file
from evoeye.batch import plan_uniform, run_batch
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import EfficiencyConfig, parse_regime
from evoeye.results.efficiency.stream import collisions, draw_on
from evoeye.scenarios import get_scenario
from evoeye.sim.episode import RunSpec
from evoeye.sim.runner import run_spec
from evoeye.store import Warehouse, ingest

SETS = ("pool", "test", "val", "oracle")  # uniform batches, seeds data_seed + their index
BOUNDARY_BATCH = "boundary"
BOUNDARY_FILE = "boundary.json"
VAL_FILE = "val-collisions.json"
VAL_MAX_CHUNKS = 100  # further validation runs drawn at most, in units of val_runs
VAL_DRAW_FILE = "val-draw.json"  # the further runs drawn (`stream.draw_on`'s record)
Say = Callable[[str], None]


def regime_root(root: DataRoot, regime: str) -> DataRoot:
    """The data root of a regime under the study's root."""
    scenario, profile = parse_regime(regime)
    return DataRoot(root.path / "efficiency" / f"{scenario}--{profile}")


def batch_name(name: str, config: EfficiencyConfig) -> str:
    """The batch of a uniform set: `<set>-seed<its seed>`."""
    return f"{name}-seed{config.data_seed + SETS.index(name)}"


def uniform_sizes(config: EfficiencyConfig) -> dict[str, int]:
    return {"pool": config.pool_runs, "test": config.test_runs, "val": config.val_runs,
            "oracle": config.oracle_runs}


def prepare_regime(root: DataRoot, regime: str, config: EfficiencyConfig, *, workers: int = 1,
                   say: Say | None = None) -> DataRoot:
    """Simulate (or resume) and ingest a regime's uniform sets, then its boundary set; its
    data root."""
    say = say or (lambda msg: None)
    scenario, profile = parse_regime(regime)
    data = regime_root(root, regime)
    for name, n in uniform_sizes(config).items():
        seed = config.data_seed + SETS.index(name)
        say(f"{regime}: {name} set, {n} runs (seed {seed})")
        run_batch(plan_uniform(scenario, n, seed, batch=batch_name(name, config), ads=profile),
                  data, workers=workers)
    if config.val_collisions:
        extend_validation(data, regime, config, workers=workers, say=say)
    say(f"{regime}: ingesting")
    ingest(data, workers=workers)
    if not (data.path / BOUNDARY_FILE).is_file():
        build_boundary_set(data, regime, config, workers=workers, say=say)
        ingest(data, workers=workers)
    return data


@dataclass
class _Pair:
    """One bisection: the safe and the colliding end (normalised θ) and their runs."""

    safe_u: np.ndarray
    hit_u: np.ndarray
    seed: int
    safe_id: str = ""
    hit_id: str = ""
    alive: bool = True


def boundary_pairs(params: np.ndarray, collided: np.ndarray, space, n_pairs: int,
                   rng: np.random.Generator) -> list[tuple[int, int]]:
    """(colliding row, nearest safe row) pairs in normalised θ: up to n_pairs colliding rows in
    a seeded order, each with the safe row nearest to it (Euclidean)."""
    u = space.normalise(params)
    hits, safe = np.flatnonzero(collided), np.flatnonzero(~collided)
    if len(hits) == 0 or len(safe) == 0:
        raise ValueError("the boundary set needs both safe and colliding pool runs")
    order = rng.permutation(hits)[:n_pairs]
    d = ((u[order, None, :] - u[None, safe, :]) ** 2).sum(axis=-1)  # (pairs, safe)
    return [(int(h), int(safe[j])) for h, j in zip(order, d.argmin(axis=1), strict=True)]


def build_boundary_set(data: DataRoot, regime: str, config: EfficiencyConfig, *,
                       workers: int = 1, say: Say | None = None) -> list[str]:
    """Bisect pairs of pool runs across the failure boundary (module doc); the set's ids,
    also written to `boundary.json`."""
    say = say or (lambda msg: None)
    scenario, profile = parse_regime(regime)
    space = get_scenario(scenario)
    pool = Warehouse(data).sql(
        "SELECT params, collided FROM scenarios WHERE batch = ? AND status = 'ok' "
        "ORDER BY scenario_id", [batch_name("pool", config)]).to_pydict()
    params = np.array(pool["params"], float)
    collided = np.array(pool["collided"], bool)
    seed = config.data_seed + len(SETS)
    rng = np.random.default_rng(seed)
    rows = boundary_pairs(params, collided, space, config.boundary_pairs, rng)
    seeds = np.random.SeedSequence(seed).generate_state(len(rows))
    u = space.normalise(params)
    pairs = [_Pair(u[s], u[h], int(k)) for (h, s), k in zip(rows, seeds, strict=True)]

    def spec(u_point: np.ndarray, pair: _Pair) -> RunSpec:
        return run_spec(scenario, space.denormalise(u_point), pair.seed, batch=BOUNDARY_BATCH,
                        source="boundary", ads=profile)

    def simulate(specs: list[RunSpec]) -> dict[str, bool | None]:
        results = run_batch(specs, data, workers=workers).results
        return {r.scenario_id: (r.collided if r.status == "ok" else None) for r in results}

    say(f"{regime}: boundary set, {len(pairs)} pairs, {config.boundary_steps} bisections")
    ends = [(spec(p.safe_u, p), spec(p.hit_u, p)) for p in pairs]
    outcome = simulate([s for both in ends for s in both])
    for p, (safe, hit) in zip(pairs, ends, strict=True):
        p.safe_id, p.hit_id = safe.scenario_id, hit.scenario_id
        p.alive = outcome[safe.scenario_id] is False and outcome[hit.scenario_id] is True
    for step in range(config.boundary_steps):
        live = [p for p in pairs if p.alive]
        mids = [spec((p.safe_u + p.hit_u) / 2, p) for p in live]
        outcome = simulate(mids)
        for p, m in zip(live, mids, strict=True):
            hit = outcome[m.scenario_id]
            if hit is None:  # a failed run cannot say which side it is on
                p.alive = False
            elif hit:
                p.hit_u, p.hit_id = (p.safe_u + p.hit_u) / 2, m.scenario_id
            else:
                p.safe_u, p.safe_id = (p.safe_u + p.hit_u) / 2, m.scenario_id
        say(f"{regime}: bisection {step + 1}/{config.boundary_steps}, "
            f"{sum(p.alive for p in pairs)} pairs")
    ids = sorted(i for p in pairs if p.alive for i in (p.safe_id, p.hit_id))
    with atomic_file(data.path / BOUNDARY_FILE) as f:
        f.write(json.dumps({"regime": regime, "pairs": len(pairs),
                            "bracketing": len(ids) // 2, "steps": config.boundary_steps,
                            "scenario_ids": ids}, indent=1).encode())
    return ids


def boundary_ids(data: DataRoot) -> list[str]:
    """The boundary set's run ids (`build_boundary_set`)."""
    return json.loads((data.path / BOUNDARY_FILE).read_bytes())["scenario_ids"]


def extend_validation(data: DataRoot, regime: str, config: EfficiencyConfig, *,
                      workers: int = 1, say: Say | None = None) -> list[str]:
    """`draw_collisions` for the study's validation batch and `config.val_collisions`."""
    return draw_collisions(data, regime, config.data_seed + SETS.index("val"), config.val_runs,
                           config.val_collisions, batch_name("val", config), workers=workers,
                           say=say)


def draw_collisions(data: DataRoot, regime: str, seed: int, n: int, want: int, batch: str, *,
                    workers: int = 1, say: Say | None = None) -> list[str]:
    """Draw the stream of the uniform batch `batch` (`n` runs of `seed`) on until it holds
    `want` colliding runs (module doc); the ids of the further colliding runs kept, in stream
    order (none when the batch holds enough), also written to `val-collisions.json`.
    ValueError, with `val-collisions.json` not written, if VAL_MAX_CHUNKS × n further runs do
    not hold enough (the draw's record keeps what was simulated)."""
    scenario, profile = parse_regime(regime)
    base = run_batch(plan_uniform(scenario, n, seed, batch=batch, ads=profile), data,
                     workers=workers).collisions
    need = want - base
    chunks = draw_on(data, regime, seed, n, n, f"val-more-seed{seed}", data.path / VAL_DRAW_FILE,
                     want, VAL_MAX_CHUNKS, held=base, workers=workers, say=say)
    kept, drawn = collisions(chunks), len(chunks) * n
    if len(kept) < need:
        raise ValueError(f"{regime}: {drawn} further validation runs held {len(kept)} "
                         f"collisions, {need} short of val_collisions = {want} with the batch's "
                         f"{base}: ask fewer")
    kept = kept[:max(need, 0)]
    with atomic_file(data.path / VAL_FILE) as f:
        f.write(json.dumps({"regime": regime, "val_runs": n, "seed": seed,
                            "val_collisions": want, "batch_collisions": base,
                            "drawn": drawn, "scenario_ids": kept}, indent=1).encode())
    return kept


def val_extra_ids(data: DataRoot, config: EfficiencyConfig) -> list[str]:
    """The further colliding validation runs `extend_validation` kept for this config; [] for
    val_collisions = 0. ValueError if they were kept for another config."""
    return kept_collisions(data, config.data_seed + SETS.index("val"), config.val_runs,
                           config.val_collisions)


def kept_collisions(data: DataRoot, seed: int, n: int, want: int) -> list[str]:
    """The further colliding runs `draw_collisions` kept for a batch of `n` runs of `seed` and
    `want` collisions; [] for want = 0. ValueError if they were kept for other settings."""
    if not want:
        return []
    path = data.path / VAL_FILE
    found = json.loads(path.read_bytes()) if path.is_file() else {}
    asked = {"val_runs": n, "seed": seed, "val_collisions": want}
    if {k: found.get(k) for k in asked} != asked:
        raise ValueError(f"{path} does not hold the validation runs of {asked}: prepare the "
                         "regime's data again")
    return found["scenario_ids"]
