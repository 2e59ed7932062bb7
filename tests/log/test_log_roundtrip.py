"""Episode → MCAP → RunLog gives back the same metadata, messages, times and road map."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from evoeye.log import CHANNELS, TOPICS, RunLog, read_run, write_episode
from evoeye.log.channels import FRAME_CHANNELS, log_time_ns
from evoeye.log.records import run_values
from evoeye.log.synthetic import synthetic_episode
from evoeye.sim.episode import STATUS_FAILED, Episode

ADS_TOPICS = {
    TOPICS.localization: "localization",
    TOPICS.obstacles: "obstacles",
    TOPICS.predictions: "predictions",
    TOPICS.plan: "plan",
    TOPICS.control: "control",
}


def as_json(value: Any) -> Any:
    """A value as it comes back from JSON: arrays and numpy scalars as Python lists/numbers."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if isinstance(value, tuple):
        return list(value)
    return value


def test_metadata_round_trips_typed(episode: Episode, run: RunLog) -> None:
    assert run.metadata == run_values(episode)
    md = run.metadata
    assert isinstance(md["seed"], int) and isinstance(md["collided"], bool)
    assert all(isinstance(v, float) for v in md["params"])
    assert md["params"] == list(episode.spec.params)
    assert md["param_names"][0] == "ego_speed_mps" and len(md["param_names"]) == len(md["params"])
    assert md["status"] == "ok" and md["reason"] == ""


def test_every_frame_channel_has_one_message_per_frame(episode: Episode, run: RunLog) -> None:
    for channel in FRAME_CHANNELS:
        assert len(run.messages(channel.topic)) == len(episode.frames), channel.topic
    assert len(run.messages(TOPICS.map)) == 1
    assert set(run.topics) == set(TOPICS)


def test_log_times_are_simulation_times(episode: Episode, run: RunLog) -> None:
    expected = [log_time_ns(f.scene.t_s) for f in episode.frames]
    assert expected[1] - expected[0] == 50_000_000  # 20 Hz
    for topic in ADS_TOPICS | {TOPICS.ground_truth: "", TOPICS.scene: ""}:
        assert run.log_times_ns(topic) == expected
        assert [t for t, _ in run.messages(topic)] == expected


@pytest.mark.parametrize("topic", list(ADS_TOPICS))
def test_ads_messages_round_trip_exactly(episode: Episode, run: RunLog, topic: str) -> None:
    attr = ADS_TOPICS[topic]
    for frame, (_, got) in zip(episode.frames, run.messages(topic), strict=True):
        sent = getattr(frame.messages, attr).to_dict()
        assert got == {k: as_json(v) for k, v in sent.items()}


def test_ground_truth_round_trips_exactly(episode: Episode, run: RunLog) -> None:
    for frame, (_, got) in zip(episode.frames, run.messages(TOPICS.ground_truth), strict=True):
        scene = frame.scene
        assert got["t_s"] == scene.t_s
        assert got["actor_id"] == scene.actor_id.tolist()
        assert got["x_m"] == scene.x_m.tolist()
        assert got["vx_mps"] == scene.vx_mps.tolist()
        assert got["vy_mps"] == scene.vy_mps.tolist()
        assert got["crashed"] == scene.crashed.tolist()
        assert got["ego_collision"] is bool(scene.ego_collision)
        assert got["collision_actor"] == scene.collision_actor
        assert set(got) == set(CHANNELS[TOPICS.ground_truth].fields)


def test_road_map_round_trips(episode: Episode, run: RunLog) -> None:
    rm, got = episode.road_map, run.road_map
    assert got is not None and got.name == rm.name
    assert [lane.lane_id for lane in got.lanes] == [lane.lane_id for lane in rm.lanes]
    for a, b in zip((*got.lanes, got.route), (*rm.lanes, rm.route), strict=True):
        np.testing.assert_array_equal(a.points, b.points)
        assert (a.width_m, a.speed_limit_mps) == (b.width_m, b.speed_limit_mps)


def test_topic_subset_loads_only_those(log_path: Path, episode: Episode) -> None:
    run = read_run(log_path, topics=[TOPICS.localization])
    assert run.topics == (TOPICS.localization,)
    assert len(run.messages(TOPICS.localization)) == len(episode.frames)
    with pytest.raises(KeyError, match="not loaded"):
        run.messages(TOPICS.obstacles)
    assert read_run(log_path, topics=[]).topics == ()


def test_failed_run_without_frames_is_written(tmp_path: Path) -> None:
    ep = synthetic_episode(n_frames=0, seed=3, failed=True)
    run = read_run(write_episode(ep, tmp_path / "failed.mcap"))
    assert run.metadata["status"] == STATUS_FAILED
    assert run.metadata["reason"] == ep.outcome.reason != ""
    assert run.metadata["min_distance_m"] is None and run.metadata["collision_time_s"] is None
    for channel in FRAME_CHANNELS:
        assert run.messages(channel.topic) == []
    assert len(run.messages(TOPICS.map)) == 1  # the road is still drawn
    assert run.road_map is not None


def test_same_episode_gives_identical_bytes(episode: Episode, tmp_path: Path) -> None:
    a = write_episode(episode, tmp_path / "a.mcap").read_bytes()
    b = write_episode(episode, tmp_path / "b.mcap").read_bytes()
    assert a == b


def test_overwrite_replaces_the_log(episode: Episode, tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    path.write_bytes(b"old")
    assert read_run(write_episode(episode, path)).metadata["seed"] == episode.spec.seed
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]


def test_schema_ids_name_the_versions(run: RunLog) -> None:
    assert set(run.schema_ids) == set(TOPICS)
    assert run.schema_ids[TOPICS.localization] == "urn:evoeye:schemas:mcap:localization.v1"
    assert run.schema_ids[TOPICS.scene] == run.schema_ids[TOPICS.map]


def test_frames_without_obstacles_round_trip(tmp_path: Path) -> None:
    ep = synthetic_episode(n_frames=5, seed=2, n_obstacles=0)
    run = read_run(write_episode(ep, tmp_path / "empty-road.mcap"))
    (_, first), *_ = run.messages(TOPICS.predictions)
    assert first["x_m"] == [] and first["track_id"] == []
    (_, update), *_ = run.messages(TOPICS.scene)
    assert [e["id"] for e in update["entities"]] == ["actor/0", "predictions", "plan"]


def test_a_log_written_before_profiles_existed_reads_as_the_default_profile(
        episode: Episode) -> None:
    from evoeye.log.records import decode_run, encode_run

    record = encode_run(run_values(episode))
    assert decode_run(record)["ads_profile"] == "default"
    older = {k: v for k, v in record.items() if k != "ads_profile"}
    assert decode_run(older) == decode_run(record)
    with pytest.raises(ValueError, match="missing fields \\['seed'\\]"):  # others stay required
        decode_run({k: v for k, v in record.items() if k != "seed"})


def test_the_world_is_recorded_only_when_it_is_not_the_default(episode: Episode) -> None:
    from dataclasses import replace

    from evoeye.log.records import decode_run, encode_run

    record = encode_run(run_values(episode))
    assert "world" not in record  # a default world's log is as before variants existed
    assert decode_run(record)["world"] == "default"
    varied = replace(episode, spec=replace(episode.spec, world="follower"))
    record = encode_run(run_values(varied))
    assert record["world"] == "follower" and decode_run(record)["world"] == "follower"
