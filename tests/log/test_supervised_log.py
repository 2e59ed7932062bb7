"""A supervised run's log: the frame channels of any run plus /supervisor (schema-valid) and
/viz/supervisor, and the trigger's record; the same run gives the same bytes."""

from __future__ import annotations

import dataclasses

import orjson
import pytest
from jsonschema import Draft202012Validator
from mcap.reader import make_reader

from evoeye.log import TOPICS, read_run, write_episode
from evoeye.log.channels import SUPERVISOR_CHANNELS, SUPERVISOR_RECORD
from evoeye.log.synthetic import synthetic_episode
from evoeye.log.writer import Supervision
from evoeye.sim.supervisor import MODES, SupervisorState

N = 12


@pytest.fixture(scope="module")
def supervised(tmp_path_factory):
    episode = synthetic_episode(n_frames=N, seed=5, n_obstacles=3)
    states = [SupervisorState(f.scene.t_s, 0.1 * (k % 10), 0.45, 0.1 * (k % 10) > 0.45,
                              k >= 5, MODES[k % len(MODES)], 1.0, -2.0 if k >= 5 else 1.0,
                              "fusion", "fusion-abc") for k, f in enumerate(episode.frames)]
    record = {"trigger": "fusion", "thresholds": [0.45, 0.5], "fallback": {"decel_mps2": 6.0}}
    folder = tmp_path_factory.mktemp("supervised")
    paths = [write_episode(episode, folder / f"run{i}.mcap", Supervision(states, record))
             for i in range(2)]
    plain = write_episode(episode, folder / "plain.mcap")
    return episode, states, record, paths, plain


def test_the_supervisor_channels_are_logged_beside_the_frame_channels(supervised) -> None:
    episode, states, record, (path, _), plain = supervised
    run = read_run(path)
    topics = {c.topic for c in SUPERVISOR_CHANNELS}
    assert topics == {"/supervisor", "/viz/supervisor"}
    assert set(run.topics) == set(TOPICS) | topics
    assert set(read_run(plain).topics) == set(TOPICS)  # an unsupervised log is unchanged
    validator = Draft202012Validator(SUPERVISOR_CHANNELS[0].schema)
    messages = [m for _, m in run.messages("/supervisor")]
    assert len(messages) == N
    for message, state in zip(messages, states, strict=True):
        validator.validate(message)
        assert message == dataclasses.asdict(state)
    labels = [m for _, m in run.messages("/viz/supervisor")]
    boxes = [any(e["id"] == "supervisor/fallback" for e in m["entities"]) for m in labels]
    assert boxes == [s.mode != "nominal" for s in states]
    assert run.metadata["scenario_id"] == episode.spec.scenario_id


def test_the_trigger_record_is_kept_and_bytes_repeat(supervised) -> None:
    _, _, record, (a, b), _ = supervised
    with open(a, "rb") as f:
        meta = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    assert {k: orjson.loads(v) for k, v in meta[SUPERVISOR_RECORD].items()} == record
    assert a.read_bytes() == b.read_bytes()
