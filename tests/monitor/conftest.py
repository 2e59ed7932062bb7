"""A tiny warehouse whose unsafe frames are easy to tell apart, and one monitor trained on it.

Ten synthetic 40-frame runs of highway-cut-in; half collide at frame 30. With H = 1 s, frames
10–29 of a colliding run are unsafe, and in exactly those frames the nearest obstacle sits 4 m
ahead of the ego and the ego brakes fully (elsewhere obstacles are ≥ 30 m away, brake ≤ 0.5).
Run ids are chosen so that split seed 0 puts 3 + 3 runs in train, 1 + 1 in val and 1 + 1 in
test (colliding + safe), so the default scenario split works too.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pytest
import torch

from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_episode
from evoeye.paths import DataRoot
from evoeye.sim.episode import Episode, Outcome
from evoeye.store import SplitSpec, ingest

# pytest -n 2 runs two workers on two cores: one intra-op thread each avoids oversubscription
torch.set_num_threads(1)

SCENARIO = "highway-cut-in"
N_FRAMES = 40
COLLISION_FRAME = 30
HORIZON_S = 1.0
RATE_HZ = 20.0
FAST = {"epochs": 20, "patience": 20, "batch_size": 32, "lr": 3e-3, "weight_decay": 1e-3}
WANTED = {"train": (3, 3), "val": (1, 1), "test": (1, 1)}  # (colliding, safe) runs per split


def split_of(scenario_id: str, spec: SplitSpec = SplitSpec()) -> str:  # noqa: B008 (frozen)
    """The split warehouse/views/06_splits.sql assigns to a round-0 run."""
    u = int(hashlib.md5(f"{spec.seed}:{scenario_id}".encode()).hexdigest()[:8], 16) / 2**32
    if u < spec.train_frac:
        return "train"
    return "val" if u < spec.train_frac + spec.val_frac else "test"


def pick_ids() -> dict[str, list[tuple[str, bool]]]:
    """Run ids (and whether each collides) filling WANTED, in a fixed order."""
    out: dict[str, list[tuple[str, bool]]] = {s: [] for s in WANTED}
    i = 0
    while any(len(out[s]) < sum(WANTED[s]) for s in WANTED):
        sid = f"tiny-{i:03d}"
        split = split_of(sid)
        have = out[split]
        if len(have) < sum(WANTED[split]):
            have.append((sid, len(have) < WANTED[split][0]))
        i += 1
    return out


def separable_episode(scenario_id: str, seed: int, collides: bool) -> Episode:
    """A synthetic episode with a plain collision precursor in its unsafe frames."""
    ep = synthetic_episode(N_FRAMES, seed=seed, n_obstacles=3)
    rng = np.random.default_rng(seed + 1000)
    unsafe_from = COLLISION_FRAME - int(HORIZON_S * RATE_HZ)
    for i, frame in enumerate(ep.frames):
        scene, msg = frame.scene, frame.messages
        hit = collides and i >= COLLISION_FRAME
        scene.crashed[:] = False
        scene.crashed[0] = hit
        scene.ego_collision = hit
        scene.collision_actor = 1 if hit else -1
        loc = msg.localization
        loc.x_m, loc.y_m, loc.heading_rad = 10.0 * frame.scene.t_s, 4.0, 0.0
        obs = msg.obstacles
        ahead = rng.uniform(30.0, 80.0, len(obs.x_m))
        danger = collides and unsafe_from <= i < COLLISION_FRAME
        if danger:
            ahead[0] = 4.0
        obs.x_m, obs.y_m = loc.x_m + ahead, np.full(len(ahead), 4.0)
        msg.control.brake = 1.0 if danger else float(rng.uniform(0.0, 0.5))
    ep.outcome = Outcome(
        status="ok", reason="", collided=collides,
        collision_time_s=COLLISION_FRAME / RATE_HZ if collides else None,
        other_actor=1 if collides else None, duration_s=N_FRAMES / RATE_HZ,
        min_distance_m=0.0 if collides else 30.0,
    )
    ep.spec = replace(ep.spec, scenario_id=scenario_id)
    return ep


@dataclass
class TinyData:
    """The tiny warehouse: root, run ids per split, episodes and logs by id, and its settings."""

    root: DataRoot
    ids: dict[str, list[str]]
    episodes: dict[str, Episode]
    logs: dict[str, Path]
    scenario: str = SCENARIO
    horizon_s: float = HORIZON_S
    fast: dict = field(default_factory=lambda: dict(FAST))  # train_monitor kwargs for tests


@pytest.fixture(scope="session")
def tiny(tmp_path_factory: pytest.TempPathFactory):
    root = DataRoot.resolve(tmp_path_factory.mktemp("monitor") / "data")
    ids: dict[str, list[str]] = {}
    episodes, logs = {}, {}
    for split, runs in pick_ids().items():
        ids[split] = [sid for sid, _ in runs]
        for seed, (sid, collides) in enumerate(runs, start=len(episodes)):
            ep = separable_episode(sid, seed, collides)
            path = root.run_log(SCENARIO, ep.spec.batch, sid)
            path.parent.mkdir(parents=True, exist_ok=True)
            logs[sid] = write_episode(ep, path)
            episodes[sid] = ep
    ingest(root)
    return TinyData(root, ids, episodes, logs)


@pytest.fixture(scope="session")
def trained(tiny) -> str:
    """One monitor version trained on the tiny train split, calibrated on its val split."""
    from evoeye.monitor.train import train_monitor

    return train_monitor(tiny.root, SCENARIO, horizon_s=HORIZON_S, seed=0, **FAST)
