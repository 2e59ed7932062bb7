"""Fixtures: small seeded episodes with known collisions, written through the real log layer."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_frame, synthetic_road_map
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.sim.episode import STATUS_FAILED, STATUS_OK, Episode, Outcome, RunSpec

RATE_HZ = 20.0


def make_episode(
    scenario_id: str,
    *,
    n_frames: int = 30,
    seed: int = 0,
    collision_frame: int | None = None,
    logical_scenario: str = "highway-cut-in",
    batch: str = "b000",
    source: str = "initial",
    round: int = 0,
    failed: bool = False,
    n_obstacles: int = 4,
) -> Episode:
    """A random episode whose ego collides from `collision_frame` on (never if None).

    Frame i is marked in its control command: throttle = i / 1000, so tests can tell which
    frame a window slot holds.
    """
    rng = np.random.default_rng(seed)
    frames = [synthetic_frame(rng, i / RATE_HZ, n_obstacles) for i in range(n_frames)]
    for i, f in enumerate(frames):
        hit = collision_frame is not None and i >= collision_frame
        f.scene.crashed[:] = False
        f.scene.crashed[0] = hit
        f.scene.ego_collision = hit
        f.scene.collision_actor = 1 if hit else -1
        f.messages.control.throttle = i / 1000.0
    collided = collision_frame is not None and collision_frame < n_frames
    outcome = Outcome(
        status=STATUS_FAILED if failed else STATUS_OK,
        reason="test failure" if failed else "",
        collided=collided,
        collision_time_s=collision_frame / RATE_HZ if collided else None,
        other_actor=1 if collided else None,
        duration_s=n_frames / RATE_HZ,
        min_distance_m=0.0 if collided else 3.5,
    )
    space = get_scenario(logical_scenario)
    spec = RunSpec(
        scenario=logical_scenario,
        params=tuple(float(v) for v in space.sample(rng)),
        seed=seed,
        scenario_id=scenario_id,
        batch=batch,
        source=source,
        round=round,
    )
    return Episode(spec, synthetic_road_map(), outcome, "evoeye-test 0.0", RATE_HZ, frames)


def write_run(root: DataRoot, episode: Episode) -> Path:
    """Write the episode's log where the simulator would."""
    spec = episode.spec
    path = root.run_log(spec.scenario, spec.batch, spec.scenario_id)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_episode(episode, path)


@pytest.fixture
def root(tmp_path: Path) -> DataRoot:
    return DataRoot.resolve(tmp_path / "data")


@pytest.fixture
def add_run(root: DataRoot) -> Callable[..., Path]:
    """add_run(scenario_id, **make_episode kwargs) writes one run's log under `root`."""

    def add(scenario_id: str, **kwargs) -> Path:
        return write_run(root, make_episode(scenario_id, **kwargs))

    return add


@pytest.fixture
def episode_factory() -> Callable[..., Episode]:
    """make_episode, for tests that need the Episode itself."""
    return make_episode


@pytest.fixture
def log_writer() -> Callable[[DataRoot, Episode], Path]:
    """write_run, for tests that write an Episode they built."""
    return write_run


def _as_layout_1(path: Path) -> None:
    """Rewrite a frame_features part as evoeye <= 0.4.0 wrote it: float lists, no layout key."""
    table = pq.read_table(path, partitioning=None)
    columns = {}
    for field in table.schema:
        col = table.column(field.name)
        if pa.types.is_fixed_size_binary(field.type):
            values = np.frombuffer(col.combine_chunks().buffers()[1], np.float32)
            width = field.type.byte_width // 4
            col = pa.ListArray.from_arrays(pa.array(np.arange(len(col) + 1, dtype=np.int32)
                                                    * width), pa.array(values))
        columns[field.name] = col
    pq.write_table(pa.table(columns), path)


@pytest.fixture
def as_layout_1() -> Callable[[Path], None]:
    """as_layout_1(path) rewrites a frame_features part in layout 1 (float lists)."""
    return _as_layout_1
