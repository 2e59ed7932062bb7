"""A seeded random Episode with the shapes of a real run, for log tests and the logging benchmark.

No simulator is involved: the numbers are random, only the shapes, dtypes and invariants (ego is
actor 0, times on the 20 Hz grid) match what `evoeye.sim` produces.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from evoeye.ads.messages import (
    PLANNING_DECISIONS,
    ControlCommand,
    FrameMessages,
    Localization,
    Obstacles,
    PlannedTrajectory,
    Predictions,
)
from evoeye.log.writer import write_episode
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.scene import Lane, RoadMap, SceneState
from evoeye.sim.episode import STATUS_FAILED, STATUS_OK, Episode, Frame, Outcome, RunSpec

SCENARIO = "highway-cut-in"


def synthetic_road_map(n_lanes: int = 3, n_points: int = 50) -> RoadMap:
    """A straight multi-lane road along +x, 4 m lanes, route = the middle lane."""
    x = np.linspace(0.0, 500.0, n_points)
    lanes = tuple(
        Lane(f"lane{i}", np.stack([x, np.full_like(x, 4.0 * i)], axis=1), 4.0, 30.0)
        for i in range(n_lanes)
    )
    return RoadMap("synthetic-highway", lanes, lanes[n_lanes // 2])


def synthetic_frame(
    rng: np.random.Generator, t_s: float, n_obstacles: int = 6, k: int = 30, p: int = 41
) -> Frame:
    """One frame: ego + n_obstacles NPCs, predictions with k points, a plan with p points."""
    n = n_obstacles + 1
    crashed = rng.random(n) < 0.1
    scene = SceneState(
        t_s=t_s,
        actor_id=np.arange(n, dtype=np.int64),
        x_m=rng.uniform(0.0, 500.0, n),
        y_m=rng.uniform(-2.0, 10.0, n),
        heading_rad=rng.uniform(-0.2, 0.2, n),
        speed_mps=rng.uniform(0.0, 35.0, n),
        accel_mps2=rng.normal(0.0, 2.0, n),
        length_m=np.full(n, 5.0),
        width_m=np.full(n, 2.0),
        crashed=crashed,
        ego_collision=bool(crashed[0]) and n > 1,
        collision_actor=int(rng.integers(1, n)) if crashed[0] and n > 1 else -1,
    )
    ids = np.arange(1, n, dtype=np.int64)
    m = n_obstacles
    messages = FrameMessages(
        localization=Localization(
            t_s,
            float(scene.x_m[0]),
            float(scene.y_m[0]),
            float(scene.heading_rad[0]),
            float(scene.speed_mps[0]),
            float(scene.accel_mps2[0]),
        ),
        obstacles=Obstacles(
            t_s,
            ids,
            ["car"] * m,
            scene.x_m[1:] + rng.normal(0, 0.3, m),
            scene.y_m[1:] + rng.normal(0, 0.3, m),
            scene.heading_rad[1:].copy(),
            rng.uniform(0, 35, m),
            rng.normal(0, 1, m),
            np.full(m, 5.0),
            np.full(m, 2.0),
            rng.uniform(0.5, 1.0, m),
        ),
        predictions=Predictions(
            t_s,
            0.1,
            ids,
            ["lane" if i % 2 else "cv" for i in range(m)],
            np.ones(m),
            np.full(m, 5.0),
            np.full(m, 2.0),
            rng.uniform(0, 500, (m, k)),
            rng.uniform(-2, 10, (m, k)),
        ),
        plan=PlannedTrajectory(
            t_s,
            PLANNING_DECISIONS[int(rng.integers(len(PLANNING_DECISIONS)))],
            float(rng.uniform(0, 35)),
            int(rng.integers(-1, n)),
            np.linspace(0.0, 4.0, p),
            rng.uniform(0, 500, p),
            rng.uniform(-2, 10, p),
            rng.uniform(-0.2, 0.2, p),
            rng.uniform(0, 35, p),
            rng.normal(0, 2, p),
        ),
        control=ControlCommand(
            t_s,
            float(rng.uniform()),
            float(rng.uniform()),
            float(rng.normal(0, 0.05)),
            float(rng.normal(0, 2)),
        ),
    )
    return Frame(scene, messages)


def synthetic_episode(
    n_frames: int = 40,
    seed: int = 0,
    *,
    n_obstacles: int = 6,
    k: int = 30,
    p: int = 41,
    rate_hz: float = 20.0,
    failed: bool = False,
) -> Episode:
    """An Episode of n_frames random frames; `failed` marks it as a failed run with a reason."""
    rng = np.random.default_rng(seed)
    frames = [synthetic_frame(rng, i / rate_hz, n_obstacles, k, p) for i in range(n_frames)]
    collided = any(f.scene.ego_collision for f in frames)
    first = next((f.scene for f in frames if f.scene.ego_collision), None)
    outcome = Outcome(
        status=STATUS_FAILED if failed else STATUS_OK,
        reason="synthetic failure: world step raised" if failed else "",
        collided=collided,
        collision_time_s=first.t_s if first is not None else None,
        other_actor=first.collision_actor if first is not None else None,
        duration_s=n_frames / rate_hz,
        min_distance_m=None if n_frames == 0 else float(rng.uniform(0.0, 20.0)),
    )
    spec = RunSpec(
        scenario=SCENARIO,
        params=tuple(float(v) for v in get_scenario(SCENARIO).sample(rng)),
        seed=seed,
        scenario_id=f"{SCENARIO}-synthetic{seed:04d}",
        batch="b000",
        source="initial",
        round=0,
    )
    return Episode(spec, synthetic_road_map(), outcome, "evoeye-test 0.0", rate_hz, frames)


def with_collision(episode: Episode, frame: int | None) -> Episode:
    """The episode with the ego colliding with actor 1 from `frame` on (never if None), in place.

    Replaces the random crashes of `synthetic_frame`; the outcome follows the frames."""
    for i, f in enumerate(episode.frames):
        hit = frame is not None and i >= frame
        f.scene.crashed[:] = False
        f.scene.crashed[0] = hit
        f.scene.ego_collision = hit
        f.scene.collision_actor = 1 if hit else -1
    collided = frame is not None and frame < len(episode.frames)
    episode.outcome = replace(
        episode.outcome, collided=collided,
        collision_time_s=episode.frames[frame].scene.t_s if collided else None,
        other_actor=1 if collided else None,
    )
    return episode


def write_synthetic_batch(root: DataRoot, batch: str, n: int, *, first_seed: int = 0,
                          n_frames: int = 100, collision_frame: int = 80) -> list[Path]:
    """n synthetic runs of SCENARIO in `batch` under `root` (ids `<batch>-00`, …, seeds
    first_seed …), the even ones colliding at `collision_frame`: data sure to hold both classes,
    whatever the simulator does. Their logs' paths."""
    paths = []
    for i in range(n):
        ep = with_collision(synthetic_episode(n_frames, first_seed + i, n_obstacles=3),
                            collision_frame if i % 2 == 0 else None)
        ep.spec = replace(ep.spec, scenario_id=f"{batch}-{i:02d}", batch=batch)
        path = root.run_log(SCENARIO, batch, ep.spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        paths.append(write_episode(ep, path))
    return paths
