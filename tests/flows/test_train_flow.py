"""The train flow through Prefect: a version with its card; fine-tuning records the parent."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from pydantic import ValidationError

from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_episode
from evoeye.paths import DataRoot
from evoeye.store import ingest
from flows.train import TrainFlowParams, train_flow

N_FRAMES, COLLISION_FRAME = 30, 20


@pytest.fixture
def root(tmp_path: Path) -> DataRoot:
    """Six synthetic runs; runs 0, 2, 4 collide at frame 20 (labels from H = 0.5 s)."""
    root = DataRoot.resolve(tmp_path / "data")
    for seed in range(6):
        ep = synthetic_episode(N_FRAMES, seed=seed, n_obstacles=2)
        hit_from = COLLISION_FRAME if seed % 2 == 0 else N_FRAMES
        for i, frame in enumerate(ep.frames):
            frame.scene.crashed[:] = False
            frame.scene.crashed[0] = frame.scene.ego_collision = i >= hit_from
        ep.outcome = replace(ep.outcome, collided=hit_from < N_FRAMES,
                             collision_time_s=hit_from / 20 if hit_from < N_FRAMES else None)
        path = root.run_log(ep.spec.scenario, ep.spec.batch, ep.spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_episode(ep, path)
    ingest(root)
    return root


def _runs(seeds: tuple[int, ...]) -> str:
    ids = ", ".join(f"'highway-cut-in-synthetic{s:04d}'" for s in seeds)
    return f"SELECT scenario_id FROM scenarios WHERE scenario_id IN ({ids})"


def test_train_flow_saves_a_version_and_fine_tunes_it(prefect_server, root: DataRoot,
                                                     latest_artifact, flow_run_names) -> None:
    params = TrainFlowParams(root=str(root.path), train_sql=_runs((0, 1, 2, 3)),
                             val_sql=_runs((4, 5)), horizon_s=0.5, epochs=2, context_len=3)
    out = train_flow(params)
    assert out["version"].startswith("fusion-") and out["parent"] is None
    assert Path(out["card"]).is_file() and set(out["thresholds"]) == {"0.05", "0.01"}
    assert 0.0 <= out["metrics"]["auroc"] <= 1.0
    md = latest_artifact("evoeye-train")
    assert md.startswith(f"# Trained {out['version']}") and "| Target FPR | Threshold |" in md
    assert flow_run_names("train-highway-cut-in-seed0")
    child = train_flow(params.model_copy(update={"init_from": out["version"], "epochs": 1,
                                                 "context_len": None}))
    assert child["parent"] == out["version"] and child["version"] != out["version"]


def test_bad_parameters_are_refused_before_anything_runs() -> None:
    with pytest.raises(ValidationError, match="modules"):
        TrainFlowParams(modules="perception,lidar")
    with pytest.raises(ValidationError, match="epochs"):
        TrainFlowParams(epochs=0)
    assert TrainFlowParams(modules="perception+prediction").modules == "perception+prediction"
