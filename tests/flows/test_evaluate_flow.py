"""The evaluate flow end to end through Prefect: report files, figures and a Markdown artifact."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_frame, synthetic_road_map
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.sim.episode import STATUS_OK, Episode, Outcome, RunSpec
from evoeye.store import ingest
from evoeye.store.scores import read_scores
from flows.evaluate import EvaluateParams, evaluate_flow

SCENARIO = "highway-cut-in"


def _episode(i: int) -> Episode:
    """Run i: random frames; even runs collide at frame 80 of 100."""
    rng = np.random.default_rng(i)
    frames = [synthetic_frame(rng, k / 20.0, 4) for k in range(100)]
    collides = i % 2 == 0
    for k, f in enumerate(frames):
        hit = collides and k >= 80
        f.scene.crashed[:] = False
        f.scene.crashed[0] = f.scene.ego_collision = hit
        f.scene.collision_actor = 1 if hit else -1
    outcome = Outcome(status=STATUS_OK, collided=collides,
                      collision_time_s=4.0 if collides else None,
                      other_actor=1 if collides else None, duration_s=5.0, min_distance_m=0.0)
    params = tuple(float(v) for v in get_scenario(SCENARIO).sample(rng))
    spec = RunSpec(SCENARIO, params, i, f"run-{i:02d}", batch="b000")
    return Episode(spec, synthetic_road_map(), outcome, "evoeye-test 0.0", 20.0, frames)


@pytest.fixture
def root(tmp_path: Path) -> DataRoot:
    root = DataRoot.resolve(tmp_path / "data")
    for i in range(30):
        ep = _episode(i)
        path = root.run_log(SCENARIO, "b000", ep.spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_episode(ep, path)
    ingest(root)
    return root


def test_evaluate_flow_writes_the_report_and_an_artifact(prefect_server: None,
                                                         root: DataRoot) -> None:
    from prefect.client.orchestration import get_client

    params = EvaluateParams(root=str(root.path), baselines=["ttc", "rss"], latency=False,
                            train_frac=0.3, val_frac=0.3, report_name="flow")
    out = evaluate_flow(params)
    (report,) = out["reports"]
    assert report["logical_scenario"] == SCENARIO
    assert [m["name"] for m in report["monitors"]] == ["ttc", "rss"]
    folder = Path(out["report_dir"])
    assert folder == root.path / "reports" / "flow"
    assert {p.name for p in folder.iterdir()} == {"rq1.md", "report.html", "report.json"}
    # one score per monitor and eligible frame (none at or after a collision) of val and test
    frames = report["dataset"]["val"]["frames"] + report["dataset"]["test"]["frames"]
    assert frames < (report["dataset"]["val"]["scenarios"]
                     + report["dataset"]["test"]["scenarios"]) * 100
    assert read_scores(root).num_rows == 2 * frames

    with get_client(sync_client=True) as client:
        artifacts = client.read_artifacts()
    (artifact,) = [a for a in artifacts if a.key == "evoeye-rq1"]
    assert artifact.data.startswith("# Monitoring effectiveness (RQ1)")
    assert "| TTC |" in artifact.data and "a warning = 3 consecutive alarm frames" in artifact.data


def test_unknown_baselines_are_refused_before_anything_runs() -> None:
    with pytest.raises(ValueError, match="unknown baseline"):
        EvaluateParams(baselines=["ttc", "nope"])
