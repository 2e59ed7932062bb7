"""RuntimeMonitor: streaming a run gives its warehouse window scores; alarms need K in a row."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.monitor.registry import load_monitor
from evoeye.monitor.replay import log_frames
from evoeye.monitor.runtime import RuntimeMonitor
from evoeye.store import load_windows


@pytest.fixture(scope="module")
def monitor(tiny, trained):
    return load_monitor(tiny.root, trained)


def test_streaming_a_run_equals_its_warehouse_window_scores(tiny, monitor) -> None:
    runtime = RuntimeMonitor(monitor)
    for sid in (tiny.ids["val"][0], tiny.ids["test"][1]):
        windows = load_windows(tiny.root, [sid], context_len=5, horizon_s=tiny.horizon_s)
        batch = monitor.score(windows)
        live = runtime.run([f.messages for f in tiny.episodes[sid].frames])
        streamed = np.array([s.score for s in live])
        # the stream scores every frame; the warehouse windows stop before a collision
        assert len(streamed) == 40 and len(batch) == (30 if tiny.episodes[sid].outcome.collided
                                                      else 40)
        np.testing.assert_allclose(streamed[:len(batch)], batch, rtol=0, atol=1e-5)
        # the same frames decoded back from the run's log
        replayed = np.array([s.score for s in runtime.run(log_frames(tiny.logs[sid]))])
        np.testing.assert_allclose(replayed[:len(batch)], batch, rtol=0, atol=1e-5)


def test_reset_starts_a_new_context(tiny, monitor) -> None:
    a, b = (tiny.episodes[sid] for sid in tiny.ids["train"][:2])
    runtime = RuntimeMonitor(monitor)
    fresh = runtime.run([f.messages for f in b.frames[:3]])
    runtime.run([f.messages for f in a.frames])
    runtime.reset()
    again = [runtime.step(f.messages) for f in b.frames[:3]]
    assert [s.score for s in again] == [s.score for s in fresh]


def test_alarm_needs_k_consecutive_frames_above_the_threshold(tiny, monitor) -> None:
    frames = [f.messages for f in tiny.episodes[tiny.ids["val"][0]].frames]
    scores = np.array([s.score for s in RuntimeMonitor(monitor).run(frames)])
    threshold = float(np.median(scores))
    for k in (1, 3):
        states = RuntimeMonitor(monitor, threshold=threshold, consecutive=k).run(frames)
        above = scores > threshold
        expected = [above[max(0, i - k + 1): i + 1].all() and i >= k - 1
                    for i in range(len(above))]
        assert [s.alarm for s in states] == expected
        assert [s.above for s in states] == above.tolist()
    calibrated = RuntimeMonitor(monitor, fpr=0.01)
    assert calibrated.threshold == monitor.thresholds.at(0.01)
    with pytest.raises(KeyError, match="0.2"):
        RuntimeMonitor(monitor, fpr=0.2)
    with pytest.raises(ValueError, match="at least 1"):
        RuntimeMonitor(monitor, consecutive=0)
