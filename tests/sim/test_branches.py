"""A branch reseeds a run's random streams at one frame: the run is unchanged before it and an
independent continuation of the same state after it, and the same branches give the same run."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.scenarios import get_scenario
from evoeye.sim.runner import run_episode, run_spec

FRAME = 60  # 3 s into the run


def spec():
    x = get_scenario("highway-cut-in").sample(np.random.default_rng(5))
    return run_spec("highway-cut-in", x, 77, ads="cautious")


def trace(ep, frames: slice) -> np.ndarray:
    """The ego's true position and the localiser's estimate (noisy: drawn from the ADS's stream)
    at every frame of `frames`."""
    return np.array([(f.scene.x_m[0], f.scene.y_m[0], f.messages.localization.x_m,
                      f.messages.localization.y_m) for f in ep.frames[frames]])


def test_a_branch_keeps_the_run_before_it_and_draws_its_future_afresh():
    plain = run_episode(spec())
    a = run_episode(spec(), branches=((FRAME, 1),))
    b = run_episode(spec(), branches=((FRAME, 2),))
    assert len(plain.frames) > FRAME + 20
    before = slice(0, FRAME)
    assert np.array_equal(trace(plain, before), trace(a, before))
    # frame FRAME's true state is the parent's; what the ADS senses there is drawn afresh
    assert np.array_equal(trace(plain, slice(FRAME, FRAME + 1))[:, :2],
                          trace(a, slice(FRAME, FRAME + 1))[:, :2])
    after = slice(FRAME, FRAME + 20)
    assert not np.array_equal(trace(plain, after), trace(a, after))
    assert not np.array_equal(trace(a, after), trace(b, after))
    again = run_episode(spec(), branches=((FRAME, 1),))
    assert np.array_equal(trace(a, slice(None)), trace(again, slice(None)))
    assert a.outcome == again.outcome


def test_branches_need_distinct_frames():
    with pytest.raises(ValueError, match="distinct frames"):
        run_episode(spec(), branches=((FRAME, 1), (FRAME, 2)))
