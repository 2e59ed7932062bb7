"""`frame_risk` over a run's frames at once gives `scene_risk` of every frame, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.batch import plan_uniform
from evoeye.criticality import frame_risk, peak_risk, scene_risk
from evoeye.scene import SceneState
from evoeye.sim.lockstep import run_lockstep


def _per_frame(scenes):
    return np.array([scene_risk(s) for s in scenes], dtype=np.float64).reshape(-1, 2)


def _same(scenes):
    got, ref = frame_risk(scenes), _per_frame(scenes)
    assert got.ttc_s.tobytes() == ref[:, 0].tobytes()
    assert got.decel_mps2.tobytes() == ref[:, 1].tobytes()
    return ref


@pytest.mark.parametrize("scenario", ["highway-cut-in", "unprotected-intersection",
                                      "occluded-crossing"])
def test_a_run_at_once_is_every_frame_alone(scenario):
    conflict = 0
    for ep in run_lockstep(plan_uniform(scenario, 6, seed=19)):
        ref = _same([f.scene for f in ep.frames])
        conflict += int(((ref[:, 0] < 3.0) | (ref[:, 1] > 2.0)).any())
    assert conflict  # frames that matter, not only an empty road


def _scene(actors):
    a = np.array(actors, dtype=float)
    n = len(a)
    return SceneState(0.0, np.arange(n), a[:, 0], a[:, 1], a[:, 2], a[:, 3], a[:, 4],
                      np.full(n, 4.5), np.full(n, 1.9), np.zeros(n, bool), False, -1)


def test_the_edge_cases_at_once_are_the_edge_cases_alone():
    frames = [
        [(0, 0, 0, 20, 0), (20, 0, 0, 10, -5), (-30, 3.5, 0, 25, 0)],  # braking lead
        [(0, 0, 0, 0, 0), (2, 0.5, 0.3, 0, 0), (40, -3.5, np.pi, 10, 1)],  # overlap, still
        [(0, 0, 0, -2, 0), (10, 0, 0.1, 5, -1), (0, 20, -np.pi / 2, 12, 0)],  # reversing
        [(5, 5, 3.1, 15, 2), (5, 30, 3.1, 15, -8), (100, 100, 1, 1, 1)],
    ]
    ref = _same([_scene(f) for f in frames])
    assert ref[1, 0] == 0.0 and np.isinf(ref[:, 0]).sum() < len(frames)
    # actor counts that differ go frame by frame, to the same numbers
    mixed = [_scene(frames[0]), _scene(frames[1][:2]), _scene(frames[2])]
    _same(mixed)
    assert peak_risk([_scene(f) for f in frames]) == float(
        np.max([max(1.5 / t if t > 0 else np.inf, d / 4.0) for t, d in ref]))
