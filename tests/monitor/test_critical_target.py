"""TrainParams.target "critical" (evoeye.monitor.lookahead): a window is unsafe when its run
collides within H or comes critically close within H, judged from the logs' ground truth — on
the tiny warehouse (tests/monitor/conftest.py: H = 1 s, 20 Hz)."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.criticality import Criticality, frame_risk
from evoeye.log import read_run
from evoeye.log.channels import TOPICS, ground_truth_scene
from evoeye.monitor.lookahead import critical_target, critical_times
from evoeye.monitor.recipes import recipe_params
from evoeye.monitor.registry import load_monitor
from evoeye.monitor.train import train_monitor
from evoeye.store import RunFilter, load_windows


@pytest.fixture(scope="module")
def train(tiny):
    return load_windows(tiny.root, RunFilter(logical_scenario=tiny.scenario, split="train"),
                        horizon_s=tiny.horizon_s)


def test_a_logged_scene_reads_back_as_the_scene_it_was_written_from(tiny) -> None:
    sid = tiny.ids["train"][0]
    logged = read_run(tiny.logs[sid], [TOPICS.ground_truth]).messages(TOPICS.ground_truth)
    frames = tiny.episodes[sid].frames
    assert len(logged) == len(frames)
    for (_, message), frame in zip(logged, frames, strict=True):
        back, scene = ground_truth_scene(message), frame.scene
        assert back.t_s == scene.t_s and back.collision_actor == scene.collision_actor
        assert back.ego_collision == scene.ego_collision
        for name in ("actor_id", "x_m", "y_m", "heading_rad", "speed_mps", "accel_mps2",
                     "length_m", "width_m", "crashed"):
            np.testing.assert_array_equal(getattr(back, name), getattr(scene, name))


def test_critical_times_are_the_ground_truths_critical_frames_of_each_run(tiny) -> None:
    ids = tiny.ids["train"] + tiny.ids["val"]
    times = critical_times(tiny.root, ids + ids[:1])  # repeats are read once
    assert sorted(times) == sorted(ids)
    found = 0
    for sid in ids:
        scenes = [f.scene for f in tiny.episodes[sid].frames]
        crit = frame_risk(scenes).critical(Criticality())
        np.testing.assert_array_equal(times[sid], np.array([s.t_s for s in scenes])[crit])
        found += int(crit.sum())
    assert found > 0  # the synthetic runs do come close: the comparison is not of empties
    with pytest.raises(LookupError, match="not in the warehouse"):
        critical_times(tiny.root, ["no-such-run"])


def test_a_critical_frame_makes_the_windows_up_to_h_before_it_unsafe(train) -> None:
    start, stop = train.run_bounds()
    safe = [(a, b) for a, b in zip(start, stop, strict=True) if not train.label[a:b].any()]
    hit = [(a, b) for a, b in zip(start, stop, strict=True) if train.label[a:b].any()]
    (a, b), (c, d) = safe[0], hit[0]
    t_crit = float(train.t_s[a + 25])  # frame 25 of a safe run
    times = {str(s): np.zeros(0) for s in set(train.scenario_id)}
    times[str(train.scenario_id[a])] = np.array([t_crit])
    out = critical_target(train, times)
    frames = train.frame[a:b]
    # H = 1 s = 20 frames: an intervention at frames 5 … 25 is justified, none other
    np.testing.assert_array_equal(out.label[a:b], ((frames >= 5) & (frames <= 25)).astype(int))
    np.testing.assert_array_equal(out.label[c:d], train.label[c:d])  # collisions stay unsafe
    others = np.ones(len(train), bool)
    others[a:b] = False
    np.testing.assert_array_equal(out.label[others], train.label[others])
    assert out.features is train.features and out.label.dtype == np.int8


def test_a_monitor_trained_on_critical_approaches_says_so_on_its_card(tiny) -> None:
    with pytest.raises(ValueError, match="unknown target 'near'"):
        recipe_params(target="near")
    base = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=0,
                         **tiny.fast)
    critical = train_monitor(tiny.root, tiny.scenario, horizon_s=tiny.horizon_s, seed=0,
                             target="critical", **tiny.fast)
    assert critical != base
    params = load_monitor(tiny.root, critical).card["hyperparameters"]
    assert params["target"] == "critical"
    assert "target" not in load_monitor(tiny.root, base).card["hyperparameters"]
