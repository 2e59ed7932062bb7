"""The context-only control: clock, ego speed and position only; trained, calibrated, evaluated
and stored like the other baselines."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.baselines.context import (
    CONTEXT_INPUTS,
    WHERE_WHEN_INPUTS,
    ContextOnlyMonitor,
    context_inputs,
    train_context_only,
)
from evoeye.evaluation.metrics import auroc
from evoeye.monitor.families import MonitorLoadError
from evoeye.store.features import CONTROL_FEATURES, FEATURES, FrameFeatures
from evoeye.store.windows import Windows

SPEED = CONTROL_FEATURES.index("ego_speed_mps")


def clock_windows(n_runs: int, seed: int, label_of_time) -> Windows:
    """L = 1 windows of 100-frame runs at 20 Hz, random speed and position; label(t, rng)."""
    rng = np.random.default_rng(seed)
    t = np.tile(np.arange(100) / 20.0, n_runs)  # (B,)
    n = len(t)
    f = FrameFeatures.empty(n, FEATURES)
    f.control[:, SPEED] = rng.uniform(0, 30, n)
    ids = np.repeat([f"r{i}" for i in range(n_runs)], 100).astype(object)
    frame = np.tile(np.arange(100, dtype=np.int32), n_runs)
    label = label_of_time(t, rng).astype(np.int8)
    return Windows(f, np.arange(n)[:, None], np.ones((n, 1), bool), label, ids, frame, t, 3.0,
                   FEATURES, rng.uniform(-200, 200, (n, 2)))


def scripted(t: np.ndarray, rng) -> np.ndarray:
    return (t >= 2.0) & (t < 3.5)  # every run's danger comes at the same moment


def unscripted(t: np.ndarray, rng) -> np.ndarray:
    return rng.random(len(t)) < 0.2  # danger at no particular time or place


def test_inputs_are_the_clock_the_speed_and_the_position() -> None:
    w = clock_windows(2, 0, scripted)
    x = context_inputs(w)
    assert CONTEXT_INPUTS == ("t_s", "ego_speed_mps", "ego_x_m", "ego_y_m")
    np.testing.assert_array_equal(x[:, 0], w.t_s)
    np.testing.assert_allclose(x[:, 1], w.features.control[:, SPEED])
    np.testing.assert_array_equal(x[:, 2:], w.ego_xy_m)


@pytest.mark.parametrize(("label_of_time", "lo", "hi"), [(scripted, 0.95, 1.0),
                                                         (unscripted, 0.4, 0.6)])
def test_scores_high_only_when_the_label_follows_the_clock(label_of_time, lo, hi) -> None:
    monitor = train_context_only(clock_windows(20, 1, label_of_time))
    test = clock_windows(10, 2, label_of_time)
    s = monitor.score(test)
    assert s.shape == (len(test),) and s.min() >= 0.0 and s.max() <= 1.0
    assert lo <= auroc(s, test.label) <= hi


def test_same_data_same_version_and_a_saved_model_round_trips(tmp_path) -> None:
    w = clock_windows(5, 3, scripted)
    a, b = train_context_only(w), train_context_only(w)
    assert a.version == b.version and a.version.startswith("ctx-")
    assert train_context_only(clock_windows(5, 4, scripted)).version != a.version
    folder = a.save(tmp_path)
    back = ContextOnlyMonitor.load(folder)
    np.testing.assert_array_equal(back.score(w), a.score(w))
    assert back.version == a.version and back.name == "context-only"
    (folder / "model.pkl").write_bytes((folder / "model.pkl").read_bytes() + b"x")
    with pytest.raises(MonitorLoadError, match="sha256 differs"):
        ContextOnlyMonitor.load(folder)


def test_one_class_is_refused() -> None:
    with pytest.raises(ValueError, match="both classes"):
        train_context_only(clock_windows(2, 0, lambda t, rng: np.zeros(len(t), bool)))


def test_the_where_when_control_does_not_see_the_speed(tmp_path) -> None:
    def fast(w: Windows) -> Windows:  # danger where the ego is fast, at any time and place
        w.label[:] = w.features.control[:, SPEED] > 20.0
        return w

    train, test = fast(clock_windows(20, 5, scripted)), fast(clock_windows(10, 6, scripted))
    x = context_inputs(test, WHERE_WHEN_INPUTS)
    assert WHERE_WHEN_INPUTS == ("t_s", "ego_x_m", "ego_y_m") and x.shape == (len(test), 3)
    np.testing.assert_array_equal(x[:, 1:], test.ego_xy_m)
    full, where_when = train_context_only(train), train_context_only(train, name="where-when")
    assert auroc(full.score(test), test.label) > 0.95
    assert 0.4 <= auroc(where_when.score(test), test.label) <= 0.6
    assert where_when.version.startswith("ww-") and where_when.inputs == WHERE_WHEN_INPUTS
    back = ContextOnlyMonitor.load(where_when.save(tmp_path))
    assert back.name == "where-when" and back.version == where_when.version
    np.testing.assert_array_equal(back.score(test), where_when.score(test))
