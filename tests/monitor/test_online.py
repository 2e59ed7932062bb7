"""Online scorers: streaming a run frame by frame gives the scores of its warehouse windows."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.baselines import TTC2DMonitor
from evoeye.monitor.online import (
    FrameInputs,
    FusionScorer,
    WindowScorer,
    online_scorer,
)
from evoeye.monitor.registry import load_monitor
from evoeye.store import load_windows


@pytest.fixture(scope="module")
def monitor(tiny, trained):
    return load_monitor(tiny.root, trained)


def _stream(scorer, episode) -> np.ndarray:
    scorer.reset()
    return np.array([scorer.score(FrameInputs.of(f.messages)) for f in episode.frames])


@pytest.mark.parametrize("split", ["val", "test"])
def test_window_scorer_equals_the_warehouse_windows_at_l_1_and_l_5(tiny, monitor,
                                                                    split) -> None:
    """L = 5 pads the start of the run as `load_windows` does: the same scores (exactly for
    the rule; the network to float rounding, which depends on the batch size)."""
    for sid in tiny.ids[split]:
        episode = tiny.episodes[sid]
        for m, L, atol in ((TTC2DMonitor(), 1, 0.0), (monitor, 5, 1e-6)):
            windows = load_windows(tiny.root, [sid], context_len=L, horizon_s=tiny.horizon_s)
            batch = m.score(windows)
            streamed = _stream(WindowScorer(m, L), episode)
            np.testing.assert_allclose(streamed[: len(batch)], batch, rtol=0, atol=atol)


def test_the_fusion_monitor_streams_through_its_runtime_monitor(tiny, monitor) -> None:
    scorer = online_scorer(monitor)
    assert isinstance(scorer, FusionScorer)
    assert isinstance(online_scorer(TTC2DMonitor()), WindowScorer)
    sid = tiny.ids["val"][0]
    windows = load_windows(tiny.root, [sid], context_len=5, horizon_s=tiny.horizon_s)
    streamed = _stream(scorer, tiny.episodes[sid])
    # the logits: thresholds on them do not saturate where float32 risks reach 1.0
    np.testing.assert_allclose(streamed[: len(windows)], monitor.logits(windows), atol=1e-4)
    assert np.ptp(streamed) > 1.0
    again = _stream(scorer, tiny.episodes[sid])  # reset starts a new run
    np.testing.assert_array_equal(again, streamed)


def test_frame_inputs_carry_time_and_ego_position(tiny) -> None:
    frame = tiny.episodes[tiny.ids["val"][0]].frames[7]
    inputs = FrameInputs.of(frame.messages)
    loc = frame.messages.localization
    assert len(inputs.features) == 1 and inputs.t_s == loc.t_s
    assert inputs.ego_xy_m == (loc.x_m, loc.y_m)
