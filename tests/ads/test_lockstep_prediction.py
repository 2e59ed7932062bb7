"""Batched prediction (`evoeye.ads.lockstep.prediction`) against each run's own predictor.

The obstacles are those of real runs (built and stepped as `run_episode` does), frame by frame,
for every scenario and two ADS profiles (whose prediction configs differ), batched one run at a
time, per regime and all mixed; plus dense synthetic obstacles on the same maps, which reach
every mode (lane continuations, changes, yield, cv) with many obstacles per run. Equality is of
every field, bit for bit. (The intersection's runs hold modes whose probabilities differ in the
last bits: ordering them by a key on the batch's obstacle index, not the run's, fails here.)
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from evoeye.ads.config import ADSConfig
from evoeye.ads.lockstep import prediction as lockstep_prediction
from evoeye.ads.lockstep.prediction import predict_batch
from evoeye.ads.messages import PREDICTION_MODES, Localization, Obstacles, Predictions
from evoeye.ads.prediction import IntentPredictor
from evoeye.batch import plan_uniform
from evoeye.scenarios import SCENARIOS
from evoeye.scene import RoadMap
from evoeye.sim.runner import RunLoop

PROFILES = ("default", "cautious")
RUNS = 5  # runs per regime
FRAMES = 80
ARRAYS = ("track_id", "mode_prob", "length_m", "width_m", "x_m", "y_m")


def assert_same(batched: Predictions, per_run: Predictions) -> None:
    assert type(batched.t_s) is type(per_run.t_s) and batched.t_s == per_run.t_s
    assert type(batched.dt_s) is type(per_run.dt_s) and batched.dt_s == per_run.dt_s
    assert batched.model == per_run.model
    for name in ARRAYS:
        a, b = getattr(batched, name), getattr(per_run, name)
        assert (a.dtype, a.shape) == (b.dtype, b.shape), name
        assert a.tobytes() == b.tobytes(), name


MAPS: dict[str, RoadMap] = {}  # each scenario's map, as its runs build it


def step_regime(scenario: str, profile: str) -> list[list[tuple]]:
    """Per frame, (predictor, obstacles, ego, predictions) of every run still going."""
    loops = [RunLoop(spec) for spec in plan_uniform(scenario, RUNS, seed=11, ads=profile)]
    for loop in loops:
        loop.start()
    MAPS[scenario] = loops[0].road_map
    frames = []
    for k in range(FRAMES):
        frame = []
        for loop in loops:
            if loop.done:
                continue
            scene = loop.observe(k)
            msgs = loop.driver.step(scene)
            frame.append((loop.driver.predictor, msgs.obstacles, msgs.localization,
                          msgs.predictions))
            if loop.record(k, scene, msgs):
                loop.world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad, loop.dt)
        frames.append(frame)
    return frames


@pytest.fixture(scope="module")
def regimes() -> dict[tuple[str, str], list[list[tuple]]]:
    return {(s, p): step_regime(s, p) for s in SCENARIOS for p in PROFILES}


@pytest.fixture
def groups(monkeypatch) -> list[int]:
    """The number of runs in each group predict_batch predicts at once (of two runs or more:
    a group of one is its own predictor's)."""
    sizes: list[int] = []
    group = lockstep_prediction._predict_group

    def spy(p, obstacles, arrays):
        sizes.append(len(obstacles))
        return group(p, obstacles, arrays)

    monkeypatch.setattr(lockstep_prediction, "_predict_group", spy)
    return sizes


def check(rows: list[tuple]) -> None:
    preds = predict_batch([r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows])
    assert len(preds) == len(rows)
    for pred, row in zip(preds, rows, strict=True):
        assert_same(pred, row[3])


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("profile", PROFILES)
def test_every_frame_of_real_runs_batched_and_alone(regimes, groups, scenario, profile):
    frames = regimes[scenario, profile]
    assert len(frames) == FRAMES and all(len(f) == RUNS for f in frames)
    for frame in frames:
        check(frame)
        for row in frame:  # B = 1
            check([row])
    # one map and one config per regime: every frame's runs with obstacles form one group
    expected = []
    for frame in frames:
        n = sum(len(r[1].x_m) > 0 for r in frame)
        expected += [n] * (n > 1)
    assert groups == expected


def test_regimes_mixed_in_one_batch_group_by_map_and_config(regimes, groups):
    empty = rows = 0
    for k in range(FRAMES):
        frame = [row for frames in regimes.values() for row in frames[k]]
        rng = np.random.default_rng(k)
        frame = [frame[i] for i in rng.permutation(len(frame))]
        groups.clear()
        check(frame)
        assert len(groups) == sum(sum(len(r[1].x_m) > 0 for r in f[k]) > 1
                                  for f in regimes.values())
        empty += sum(len(r[1].x_m) == 0 for r in frame)
        rows += sum(len(r[3].model) for r in frame)
    assert empty > 0 and rows > 0  # runs without obstacles occurred, and in the batch


def test_a_map_without_lanes_is_constant_velocity(regimes, groups):
    config = ADSConfig().prediction
    frames = regimes["highway-cut-in", "default"]
    for frame in frames[::7]:
        predictors = [IntentPredictor(RoadMap.empty("none"), config) for _ in frame]
        obstacles, egos = [r[1] for r in frame], [r[2] for r in frame]
        batched = predict_batch(predictors, obstacles, egos)
        for p, o, e, pred in zip(predictors, obstacles, egos, batched, strict=True):
            assert_same(pred, p.predict(o, e))
            assert set(pred.model) <= {"cv"}
    assert groups and max(groups) > 1


def test_other_predictors_and_configs_differing_in_a_zero_sign_are_not_grouped(regimes, groups):
    class Shifted(IntentPredictor):
        def predict(self, obstacles, ego):
            pred = super().predict(obstacles, ego)
            pred.x_m = pred.x_m + 1.0
            return pred

    frame = [r for r in regimes["highway-cut-in", "default"][40] if len(r[1].x_m)]
    assert len(frame) >= 5
    road_map = MAPS["highway-cut-in"]
    c = frame[0][0].c
    predictors = [Shifted(road_map, c), IntentPredictor(road_map, replace(c, yield_prior=0.0)),
                  IntentPredictor(road_map, replace(c, yield_prior=-0.0))]
    predictors += [r[0] for r in frame[len(predictors):]]
    obstacles, egos = [r[1] for r in frame], [r[2] for r in frame]
    batched = predict_batch(predictors, obstacles, egos)
    for p, o, e, pred in zip(predictors, obstacles, egos, batched, strict=True):
        assert_same(pred, p.predict(o, e))
    assert groups == [len(frame) - 3]  # the subclass and the two configs on their own


def synthetic(p: IntentPredictor, rng: np.random.Generator, n: int, t_s: float) -> Obstacles:
    """n obstacles about the lanes of p's map: near lanes (some across them, some reversed, some
    turning, some off the map), with lateral speeds that make lane changes likely."""
    lanes = p.lanes
    line = rng.integers(0, len(lanes.offset), n)
    s = rng.uniform(-0.05, 1.0, n) * lanes.length_m.take(line)
    g = lanes.offset.take(line) + s
    cx, cy = lanes.xy_at(g)
    h = lanes.heading_at(g)
    lat = rng.normal(0.0, 1.5, n)
    x, y = cx - lat * np.sin(h), cy + lat * np.cos(h)
    heading = h + rng.normal(0.0, 0.15, n) + np.where(rng.random(n) < 0.1, math.pi, 0.0)
    heading = np.where(rng.random(n) < 0.1, rng.uniform(-math.pi, math.pi, n), heading)
    far = rng.random(n) < 0.05
    x, y = np.where(far, x + 1.0e4, x), np.where(far, y - 3.0e3, y)
    speed = rng.uniform(0.0, 25.0, n) * (rng.random(n) > 0.1)
    v_lat = rng.normal(0.0, 1.0, n)
    vx = speed * np.cos(heading) - v_lat * np.sin(heading)
    vy = speed * np.sin(heading) + v_lat * np.cos(heading)
    return Obstacles(
        t_s=t_s, track_id=rng.permutation(n).astype(np.int64) + 1, obj_class=["car"] * n,
        x_m=x, y_m=y, heading_rad=heading, vx_mps=vx, vy_mps=vy,
        length_m=rng.uniform(4.0, 5.0, n), width_m=rng.uniform(1.8, 2.1, n),
        confidence=np.ones(n),
    )


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_dense_synthetic_obstacles_reach_every_mode(regimes, groups, scenario):
    ego = Localization(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    seen = set()
    for profile in PROFILES:
        predictors = [r[0] for r in regimes[scenario, profile][0]]
        rng = np.random.default_rng(3)
        for b in (1, 2, 7, 16):
            for k in range(12):
                ps = [predictors[i % len(predictors)] for i in range(b)]
                obstacles = [synthetic(p, rng, int(rng.integers(0, 40)), 0.05 * k) for p in ps]
                batched = predict_batch(ps, obstacles, [ego] * b)
                for p, o, pred in zip(ps, obstacles, batched, strict=True):
                    assert_same(pred, p.predict(o, ego))
                    seen.update(pred.model)
    modes = set(PREDICTION_MODES) - {"external"}
    if not any(ln for ln in regimes[scenario, "default"][0][0][0].gives_way):
        modes.discard("yield")
    assert seen == modes


@pytest.mark.parametrize("m", range(1, 13))
def test_row_reductions_do_not_depend_on_the_other_rows(m):
    """Prediction's row reductions (`w.sum(axis=1)`, `p_all.max(axis=1)`) over (n, M): each
    row's result is that of the row alone, whatever n (the batch's rows are many runs')."""
    rng = np.random.default_rng(m)
    w = rng.random((300, m)) * np.exp(rng.normal(0.0, 8.0, (300, m)))
    w[rng.random((300, m)) < 0.3] = 0.0
    w[:, -1] = np.where(rng.random(300) < 0.1, -0.0, w[:, -1])
    sums = np.array([w[i:i + 1].sum(axis=1)[0] for i in range(len(w))])
    maxes = np.array([w[i:i + 1].max(axis=1, keepdims=True)[0, 0] for i in range(len(w))])
    for n in (1, 2, 7, 8, 9, 64, 300):
        assert w[:n].sum(axis=1).tobytes() == sums[:n].tobytes()
        assert w[:n].max(axis=1, keepdims=True)[:, 0].tobytes() == maxes[:n].tobytes()
