"""A tiny labelled warehouse for the harness tests, built once per session (seconds).

Synthetic runs (random frames from `evoeye.log.synthetic`) through the real log and ingest
layers: every other run collides at frame 80 of 100, so each split holds violation and safe
runs, unsafe frames (20 … 79) and frames after a collision (80 … 99).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_frame, synthetic_road_map
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.sim.episode import STATUS_OK, Episode, Outcome, RunSpec
from evoeye.store import SplitSpec, Warehouse, ingest

RATE_HZ = 20.0
N_FRAMES = 100
COLLISION_FRAME = 80
N_RUNS = 30
SCENARIO = "highway-cut-in"
SPLITS = SplitSpec(seed=0, train_frac=0.3, val_frac=0.3)


def labelled_episode(scenario_id: str, seed: int, collides: bool) -> Episode:
    """A random run whose ego collides from COLLISION_FRAME on when `collides`."""
    rng = np.random.default_rng(seed)
    frames = [synthetic_frame(rng, i / RATE_HZ, 4) for i in range(N_FRAMES)]
    for i, f in enumerate(frames):
        hit = collides and i >= COLLISION_FRAME
        f.scene.crashed[:] = False
        f.scene.crashed[0] = hit
        f.scene.ego_collision = hit
        f.scene.collision_actor = 1 if hit else -1
    outcome = Outcome(
        status=STATUS_OK, collided=collides,
        collision_time_s=COLLISION_FRAME / RATE_HZ if collides else None,
        other_actor=1 if collides else None, duration_s=N_FRAMES / RATE_HZ,
        min_distance_m=0.0 if collides else 3.0,
    )
    params = tuple(float(v) for v in get_scenario(SCENARIO).sample(rng))
    spec = RunSpec(SCENARIO, params, seed, scenario_id, batch="b000")
    return Episode(spec, synthetic_road_map(), outcome, "evoeye-test 0.0", RATE_HZ, frames)


def build_warehouse(root: DataRoot, n_runs: int = N_RUNS) -> DataRoot:
    for i in range(n_runs):
        ep = labelled_episode(f"run-{i:02d}", seed=i, collides=i % 2 == 0)
        path = root.run_log(SCENARIO, "b000", ep.spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_episode(ep, path)
    ingest(root)
    return root


@pytest.fixture(scope="session")
def eval_root(tmp_path_factory: pytest.TempPathFactory) -> DataRoot:
    root = build_warehouse(DataRoot.resolve(tmp_path_factory.mktemp("eval") / "data"))
    kinds = Warehouse(root).sql(
        "SELECT p.split, s.collided, count(*) AS n FROM scenarios s "
        "JOIN scenario_splits($seed, $train, $val) p USING (scenario_id) GROUP BY ALL",
        {"seed": SPLITS.seed, "train": SPLITS.train_frac, "val": SPLITS.val_frac},
    ).to_pylist()
    have = {(r["split"], r["collided"]) for r in kinds}
    assert have == {(s, c) for s in ("train", "val", "test") for c in (True, False)}, kinds
    return root


@pytest.fixture(scope="session")
def new_eval_root(tmp_path_factory: pytest.TempPathFactory):
    """Builds another warehouse like eval_root's, for a test that adds to its data root."""
    return lambda: build_warehouse(DataRoot.resolve(tmp_path_factory.mktemp("eval") / "data"))


@pytest.fixture(scope="session")
def splits() -> SplitSpec:
    return SPLITS


@dataclass(frozen=True)
class Layout:
    """How the runs of `eval_root` are built."""

    scenario: str = SCENARIO
    n_frames: int = N_FRAMES
    collision_frame: int = COLLISION_FRAME
    rate_hz: float = RATE_HZ


@pytest.fixture(scope="session")
def layout() -> Layout:
    return Layout()


@pytest.fixture
def fresh_root(tmp_path: Path) -> DataRoot:
    """An empty data root of this test only."""
    return DataRoot.resolve(tmp_path / "data")
