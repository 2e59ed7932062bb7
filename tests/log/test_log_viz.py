"""The foxglove.SceneUpdate messages draw every actor, every trajectory and the road."""

from __future__ import annotations

import math

import numpy as np
import orjson
import pytest

from evoeye.log import TOPICS, RunLog, viz
from evoeye.sim.episode import Episode


def test_one_cube_entity_per_actor_plus_trajectories(episode: Episode, run: RunLog) -> None:
    for frame, (t_ns, update) in zip(episode.frames, run.messages(TOPICS.scene), strict=True):
        ids = [e["id"] for e in update["entities"]]
        actors = [f"actor/{a}" for a in frame.scene.actor_id.tolist()]
        assert ids == [*actors, "predictions", "plan"]
        assert update["deletions"][0]["type"] == viz.DELETE_ALL  # the previous frame goes
        stamp = {"sec": t_ns // 10**9, "nsec": t_ns % 10**9}
        assert all(e["timestamp"] == stamp and e["frame_id"] == "map" for e in update["entities"])
        n_pred = len(frame.messages.predictions.track_id)
        by_id = {e["id"]: e for e in update["entities"]}
        assert len(by_id["predictions"]["lines"]) == n_pred
        assert len(by_id["plan"]["lines"]) == 1


def test_actor_colours(episode: Episode, run: RunLog) -> None:
    for frame, (_, update) in zip(episode.frames, run.messages(TOPICS.scene), strict=True):
        crashed = frame.scene.crashed.tolist()
        for i, entity in enumerate(update["entities"][: frame.scene.n]):
            (cube,) = entity["cubes"]
            expected = (
                viz.CRASHED_COLOR if crashed[i] else viz.EGO_COLOR if i == 0 else viz.NPC_COLOR
            )
            assert cube["color"] == expected
            assert cube["pose"]["position"]["x"] == frame.scene.x_m[i]


def test_cube_orientation_is_the_heading(episode: Episode, run: RunLog) -> None:
    frame, (_, update) = episode.frames[0], run.messages(TOPICS.scene)[0]
    for h, entity in zip(frame.scene.heading_rad, update["entities"], strict=False):
        q = entity["cubes"][0]["pose"]["orientation"]
        assert q["z"] == pytest.approx(math.sin(h / 2))
        assert q["w"] ** 2 + q["z"] ** 2 == pytest.approx(1.0)


def test_drawn_points_keep_both_ends() -> None:
    idx = viz.drawn(30).tolist()
    assert idx[0] == 0 and idx[-1] == 29 and len(idx) == viz.MAX_LINE_POINTS
    assert viz.drawn(3).tolist() == [0, 1, 2]


def test_map_is_drawn_once_forever(episode: Episode, run: RunLog) -> None:
    ((t_ns, update),) = run.messages(TOPICS.map)
    assert t_ns == 0
    (entity,) = update["entities"]
    assert entity["id"] == "map" and entity["lifetime"] == {"sec": 0, "nsec": 0}
    assert entity["frame_locked"] is True
    rm = episode.road_map
    assert len(entity["lines"]) == len(rm.lanes) + 1  # lanes and the route
    first = [(p["x"], p["y"]) for p in entity["lines"][0]["points"]]
    lane = [tuple(xy) for xy in rm.lanes[0].points.tolist()]
    # a straight lane is drawn through its two ends only; drawn points are lane points, in order
    assert first == [lane[0], lane[-1]]


def test_curved_lanes_keep_their_shape_and_straight_runs_drop_interior_points() -> None:
    arc = np.stack([np.cos(np.linspace(0, 1.5, 30)), np.sin(np.linspace(0, 1.5, 30))], axis=1)
    line = np.stack([np.linspace(0, 100, 101), np.zeros(101)], axis=1)
    assert len(viz._corners(arc)) == 30
    np.testing.assert_array_equal(viz._corners(line), line[[0, -1]])
    bent = np.concatenate([line, line[-1] + np.stack([np.zeros(50), np.arange(1, 51)], axis=1)])
    np.testing.assert_array_equal(viz._corners(bent), bent[[0, 100, -1]])


def test_scene_update_serialises(episode: Episode) -> None:
    frame = episode.frames[0]
    update = viz.scene_update(frame.scene, frame.messages, 0)
    assert orjson.loads(orjson.dumps(update))["entities"][0]["id"] == "actor/0"
