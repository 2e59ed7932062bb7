"""A run converted from its Episode in memory equals the same run converted from its log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import orjson
import pyarrow as pa
import pytest

from evoeye.batch import plan_uniform
from evoeye.log import read_run, write_episode
from evoeye.log.episode_log import EpisodeLog
from evoeye.log.synthetic import synthetic_episode, with_collision
from evoeye.log.writer import dumps
from evoeye.sim.episode import Episode
from evoeye.sim.runner import run_episode
from evoeye.store.live_columns import live_column
from evoeye.store.log_windows import episode_run, read_logged_run
from evoeye.store.records import frames_table


def with_non_finite_values(episode: Episode) -> Episode:
    """Every third frame gets NaN, ±inf and a float beyond float32 in lists, lists of lists,
    scalars and the ego's ground truth (the log has null for each, or inf past float32)."""
    for i, frame in enumerate(episode.frames):
        if i % 3:
            continue
        msg, scene = frame.messages, frame.scene
        msg.obstacles.x_m[0] = np.nan
        msg.obstacles.confidence[1] = -np.inf
        msg.predictions.y_m[1, 2] = np.inf
        msg.plan.x_m[3] = 1e300
        msg.plan.speed_mps[0] = -0.0
        msg.localization.speed_mps = float("nan")
        msg.control.brake = float("inf")
        scene.x_m[0] = -np.inf
    return episode


def episodes() -> dict[str, Episode]:
    """Real runs of both scenarios, and synthetic ones for what real runs never hold."""
    real = {f"{s.scenario}-{i}": run_episode(s) for i, s in enumerate(
        [*plan_uniform("highway-cut-in", 2, seed=3), *plan_uniform("unprotected-intersection",
                                                                   1, seed=3)])}
    return {
        **real,
        "colliding": with_collision(synthetic_episode(60, seed=1, n_obstacles=3), 45),
        "non-finite": with_non_finite_values(synthetic_episode(30, seed=2)),
        "no obstacles": synthetic_episode(20, seed=3, n_obstacles=0),
        "failed, no frames": synthetic_episode(0, seed=4, failed=True),
    }


@pytest.fixture(scope="module")
def logged(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[str, Episode, Path]]:
    folder = tmp_path_factory.mktemp("episodes")
    return [(name, ep, write_episode(ep, folder / f"{i}.mcap"))
            for i, (name, ep) in enumerate(episodes().items())]


def test_frames_and_metadata_equal_the_logs(logged) -> None:
    for name, episode, path in logged:
        from_log, from_memory = read_run(path), EpisodeLog(episode, path)
        assert from_memory.metadata == from_log.metadata, name
        a = frames_table(from_log, "run", "part")
        b = frames_table(from_memory, "run", "part")
        assert b.schema == a.schema, name
        for column in a.column_names:
            assert b.column(column).equals(a.column(column)), (name, column)
    path = next(path for name, _, path in logged if name == "non-finite")
    nulls = frames_table(read_run(path), "run", "part").column("loc_speed_mps")
    assert nulls.null_count == 10  # the non-finite values did reach the comparison


def test_episode_run_equals_read_logged_run(logged) -> None:
    for name, episode, path in logged:
        mine = episode_run(episode, path, context_len=5, horizon_s=3.0)
        ref = read_logged_run(path, context_len=5, horizon_s=3.0)
        assert mine.path == ref.path and mine.metadata == ref.metadata, name
        assert mine.frames.equals(ref.frames), name
        for key, arr in ref.features.arrays().items():
            np.testing.assert_array_equal(mine.features.arrays()[key], arr, err_msg=name)
        assert (mine.windows is None) == (ref.windows is None), name
        if ref.windows is not None:
            np.testing.assert_array_equal(mine.windows.label, ref.windows.label)
            for key, arr in ref.windows.arrays().items():
                np.testing.assert_array_equal(mine.windows.arrays()[key], arr, err_msg=name)
    colliding = next(ep for name, ep, _ in logged if name == "colliding")
    assert episode_run(colliding, "x", 5, 3.0).windows.label.sum() > 0


FLOATS = pa.list_(pa.float32())
NESTED = pa.list_(pa.list_(pa.float32()))


@pytest.mark.parametrize(("typ", "values"), [
    (FLOATS, [np.array([1.5, np.nan, -0.0]), np.zeros(0), np.array([1e300, -np.inf])]),
    (NESTED, [np.ones((2, 3)), np.zeros((0, 3)), np.array([[np.nan, 2.0]])]),
    (pa.list_(pa.int64()), [np.array([3, -1]), np.zeros(0, np.int64)]),
    (FLOATS, [np.array([0.1, 0.2], np.float32)]),  # float32's JSON is its own shortest digits
    (FLOATS, [[0.1, float("nan")], np.array([0.3])]),  # a list where arrays are expected
    (NESTED, [[[1.0, 2.0], [3.0]]]),  # rows of unequal lengths
    (pa.list_(pa.string()), [["car", "truck"], []]),
    (pa.float64(), [1.5, float("nan"), float("-inf"), None, 2, np.float64(0.25), True]),
    (pa.float64(), [np.float32(0.1)]),
    (pa.int64(), [3, np.int64(-1)]),
    (pa.bool_(), [True, np.bool_(False)]),
    (pa.string(), ["cruise", "follow"]),
])
def test_live_column_equals_the_column_of_the_decoded_json(typ: pa.DataType, values) -> None:
    decoded = [orjson.loads(dumps(v)) for v in values]  # as the log holds them
    assert live_column(values, typ).equals(pa.array(decoded, typ))
