"""No frame at or after a run's collision enters anything learned or measured.

`eval_root` (conftest) has every other run collide at frame 80 of 100: frames 80 … 99 of those
runs are the post-collision tail a log keeps for viewing. Each test follows one path — training
windows, pos_weight, calibration, feedback, metrics, the Hard Set — and fails if such a frame
reaches it (e.g. if `eligible_frames` stopped filtering).
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest

from evoeye.store import RunFilter, Warehouse, load_windows

SCENARIO = "highway-cut-in"


@pytest.fixture(scope="module")
def collided(eval_root) -> set[str]:
    rows = Warehouse(eval_root).sql("SELECT scenario_id FROM scenarios WHERE collided")
    ids = set(rows.column("scenario_id").to_pylist())
    assert ids
    return ids


def post_collision(ids: np.ndarray, frames: np.ndarray, collided: set[str],
                   collision_frame: int) -> np.ndarray:
    """(B,) bool: the frame is at or after its run's collision."""
    hit = np.array([s in collided for s in np.asarray(ids).tolist()], bool)
    return hit & (np.asarray(frames) >= collision_frame)


def assert_pre_collision(windows, collided: set[str], layout) -> None:
    assert len(windows) > 0
    late = post_collision(windows.scenario_id, windows.frame, collided, layout.collision_frame)
    assert not late.any(), f"{int(late.sum())} post-collision frames"
    # the windows still reach the frame just before each collision (nothing else dropped)
    for sid in set(windows.scenario_id.tolist()) & collided:
        assert windows.frame[windows.scenario_id == sid].max() == layout.collision_frame - 1


def split_counts(eval_root, splits, split: str, layout) -> tuple[int, int]:
    """(eligible frames, unsafe frames) of a split at H = 3 s, by the fixture's layout."""
    rows = Warehouse(eval_root).sql(
        "SELECT s.collided, count(*) AS n FROM scenarios s "
        "JOIN scenario_splits($seed, $train, $val) p USING (scenario_id) "
        "WHERE p.split = $split GROUP BY ALL",
        {"seed": splits.seed, "train": splits.train_frac, "val": splits.val_frac,
         "split": split}).to_pylist()
    n = {r["collided"]: r["n"] for r in rows}
    unsafe = int(3 * layout.rate_hz)
    return n[True] * layout.collision_frame + n[False] * layout.n_frames, n[True] * unsafe


def test_fusion_training_windows_pos_weight_and_calibration(eval_root, splits, collided,
                                                            layout, monkeypatch) -> None:
    import evoeye.monitor.train as train_mod
    from evoeye.monitor import read_card

    seen: dict[str, object] = {}
    real_fit, real_cal = train_mod.fit, train_mod.calibrate_on_validation

    def fit(net, train, val, *args, **kwargs):
        seen["train"], seen["val"] = train, val
        return real_fit(net, train, val, *args, **kwargs)

    def calibrate(scores, val, *args, **kwargs):
        seen["calibration"] = val
        return real_cal(scores, val, *args, **kwargs)

    monkeypatch.setattr(train_mod, "fit", fit)
    monkeypatch.setattr(train_mod, "calibrate_on_validation", calibrate)
    version = train_mod.train_monitor(eval_root, SCENARIO, splits=splits, seed=7, epochs=1)
    for name in ("train", "val", "calibration"):
        assert_pre_collision(seen[name], collided, layout)
    frames, unsafe = split_counts(eval_root, splits, "train", layout)
    pos_weight = read_card(eval_root, version)["hyperparameters"]["pos_weight"]
    assert pos_weight == pytest.approx((frames - unsafe) / unsafe)


def test_aem_training_and_calibration(eval_root, splits, collided, layout,
                                      monkeypatch) -> None:
    import evoeye.baselines.aem as aem_mod
    import evoeye.monitor.calibration as cal_mod
    from evoeye.baselines.families import train_aem_version

    seen: dict[str, object] = {}
    real_train, real_cal = aem_mod.train_aem, cal_mod.calibrate_on_validation

    def train_aem(train, normal, *args, **kwargs):
        seen["train"], seen["normal"] = train, np.asarray(normal)
        return real_train(train, normal, *args, **kwargs)

    def calibrate(scores, val, *args, **kwargs):
        seen["calibration"] = val
        return real_cal(scores, val, *args, **kwargs)

    monkeypatch.setattr(aem_mod, "train_aem", train_aem)
    monkeypatch.setattr(cal_mod, "calibrate_on_validation", calibrate)
    runs = {p: RunFilter(logical_scenario=SCENARIO, split=p, splits=splits)
            for p in ("train", "val")}
    train_aem_version(eval_root, SCENARIO, train_runs=runs["train"], val_runs=runs["val"],
                      seed=11, epochs=1)
    assert_pre_collision(seen["train"], collided, layout)
    np.testing.assert_array_equal(seen["normal"], seen["train"].label == 0)  # AEM: safe only
    assert_pre_collision(seen["calibration"], collided, layout)


def test_rq1_calibration_and_metrics(eval_root, splits, collided, layout, monkeypatch) -> None:
    import evoeye.evaluation.harness as harness
    from evoeye.baselines.ttc import TTCMonitor

    seen: dict[str, object] = {}
    real_cal, real_metrics = harness.calibrate_on_validation, harness.frame_metrics

    def calibrate(scores, val, *args, **kwargs):
        seen["calibration"] = val
        return real_cal(scores, val, *args, **kwargs)

    def frame_metrics(scores, labels, *args, **kwargs):
        seen["metric_frames"] = len(labels)
        return real_metrics(scores, labels, *args, **kwargs)

    monkeypatch.setattr(harness, "calibrate_on_validation", calibrate)
    monkeypatch.setattr(harness, "frame_metrics", frame_metrics)
    report = harness.evaluate(eval_root, [TTCMonitor()], SCENARIO, splits, store_scores=False)
    assert_pre_collision(seen["calibration"], collided, layout)
    frames, unsafe = split_counts(eval_root, splits, "test", layout)
    m = report.monitors[0]
    assert seen["metric_frames"] == m.frame.frames == frames and m.frame.unsafe_frames == unsafe
    assert report.dataset["val"]["frames"] == split_counts(eval_root, splits, "val", layout)[0]


def test_feedback_from_the_warehouse_and_from_a_log(eval_root, collided, layout) -> None:
    from evoeye.evolve.campaign.scoring import warehouse_feedback
    from evoeye.store.log_windows import read_logged_run

    class Half:
        context_len = 3

        def score(self, windows):
            return np.full(len(windows), 0.5)

    ids = sorted(Warehouse(eval_root).sql("SELECT scenario_id FROM scenarios")
                 .column("scenario_id").to_pylist())[:4]
    fb = warehouse_feedback(eval_root, Half(), ids, horizon_s=3.0)
    expected = [layout.collision_frame if s in collided else layout.n_frames for s in ids]
    assert fb.n_contexts.tolist() == expected
    hit = next(s for s in ids if s in collided)
    log = Warehouse(eval_root).sql("SELECT log_path FROM scenarios WHERE scenario_id = $s",
                                   {"s": hit}).column("log_path")[0].as_py()
    logged = read_logged_run(eval_root.path / log, 3, 3.0)
    assert_pre_collision(logged.windows, collided, layout)
    warehouse = load_windows(eval_root, [hit], context_len=3, horizon_s=3.0)
    np.testing.assert_array_equal(logged.windows.frame, warehouse.frame)
    np.testing.assert_array_equal(logged.windows.label, warehouse.label)
    np.testing.assert_allclose(logged.windows.ego_xy_m, warehouse.ego_xy_m)


def test_hard_set_ignores_scores_of_post_collision_frames(eval_root, splits, collided,
                                                          layout) -> None:
    from evoeye.evolve.campaign.assess import hard_set

    wh = Warehouse(eval_root)
    frames = wh.sql("SELECT scenario_id, frame FROM frames").to_pydict()
    n = len(frames["frame"])
    scores = pa.table({"monitor_version": ["g0"] * n, "scenario_id": frames["scenario_id"],
                       "frame": frames["frame"], "score": [0.0] * n})  # misses everything
    hard = hard_set(wh, scores, monitor_version="g0", threshold=0.5, logical_scenario=SCENARIO,
                    splits=splits).to_pydict()
    assert hard["frame"], "the Hard Set should hold every test frame of the violation runs"
    late = post_collision(hard["scenario_id"], hard["frame"], collided, layout.collision_frame)
    assert not late.any()
    assert len(hard["frame"]) == split_counts(eval_root, splits, "test", layout)[1] / (
        3 * layout.rate_hz) * layout.collision_frame
