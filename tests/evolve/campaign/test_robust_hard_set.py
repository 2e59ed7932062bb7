"""The robust Hard Set query on a hand-built case: which unsafe frames a majority of k G_0s miss."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest

from evoeye.evolve.campaign.assess import frame_mask, robust_hard_set
from evoeye.log import write_episode
from evoeye.log.synthetic import synthetic_episode, with_collision
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse, ingest, load_windows

SCENARIO = "highway-cut-in"
SPLITS = SplitSpec(seed=0, train_frac=1.0, val_frac=0.0, test_batch="held")
N_FRAMES, COLLISION = 100, 80  # unsafe (H = 3 s at 20 Hz): frames 20 … 79; 80 on: not eligible
THRESHOLDS = {"m1": 0.5, "m2": 0.6, "m3": 0.4}


def _write(root: DataRoot, scenario_id: str, batch: str, seed: int, collides: bool) -> None:
    ep = with_collision(synthetic_episode(N_FRAMES, seed, n_obstacles=3),
                        COLLISION if collides else None)
    ep.spec = replace(ep.spec, scenario_id=scenario_id, batch=batch)
    path = root.run_log(SCENARIO, batch, scenario_id)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_episode(ep, path)


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> DataRoot:
    root = DataRoot.resolve(Path(tmp_path_factory.mktemp("robust")) / "data")
    _write(root, "a", "held", 1, True)
    _write(root, "b", "held", 2, True)
    _write(root, "c", "held", 3, False)
    _write(root, "t", "init", 4, True)  # a training run: never in a test set
    ingest(root)
    return root


def _scores() -> pa.Table:
    """Per monitor, a score for every frame 0 … 99 of every run (frame 99 of run c: m3 none).

    Run a, unsafe frames: 20–39 missed by all three; 40–59 by m1 and m2 (m3 scores 0.9);
    60–79 by m1 only (exactly at its threshold: a tie is a miss). Run b: every unsafe frame
    found by all. Safe frames score 0.0 (silent, which the safe side does not depend on). Run
    t (train) and the post-collision frames 80 … 99 are missed by all: they must not count."""
    rows = []
    for sid in ("a", "b", "c", "t"):
        for frame in range(N_FRAMES):
            for m, thr in THRESHOLDS.items():
                if sid == "c" and frame == 99 and m == "m3":
                    continue
                score = 0.0
                if sid == "a" and 40 <= frame < 60 and m == "m3":
                    score = 0.9
                elif sid == "a" and 60 <= frame < 80:
                    score = thr if m == "m1" else 0.99
                elif sid == "b" and 20 <= frame < 80:
                    score = 0.99
                rows.append((m, sid, frame, score))
    m, sid, frame, score = zip(*rows, strict=True)
    return pa.table({"monitor_version": list(m), "scenario_id": list(sid),
                     "frame": pa.array(frame, pa.int32()), "score": pa.array(score, pa.float32())})


def test_robust_hard_set_keeps_majority_misses_and_every_safe_test_frame(root: DataRoot) -> None:
    got = robust_hard_set(Warehouse(root), _scores(), thresholds=THRESHOLDS,
                          logical_scenario=SCENARIO, splits=SPLITS).to_pylist()
    keys = {(r["scenario_id"], r["frame"]): (r["label"], r["missed_by"]) for r in got}
    expected = {("a", f): (1, 3) for f in range(20, 40)}
    expected |= {("a", f): (1, 2) for f in range(40, 60)}
    expected |= {("a", f): (0, 3) for f in range(20)}
    expected |= {("b", f): (0, 3) for f in range(20)}
    expected |= {("c", f): (0, 3) for f in range(99)}  # frame 99: not scored by every monitor
    assert keys == expected


def test_a_single_monitor_is_the_plain_majority_of_one(root: DataRoot) -> None:
    got = robust_hard_set(Warehouse(root), _scores(), thresholds={"m3": 0.4},
                          logical_scenario=SCENARIO, splits=SPLITS).to_pylist()
    unsafe = {(r["scenario_id"], r["frame"]) for r in got if r["label"] == 1}
    assert unsafe == {("a", f) for f in range(20, 40)}  # m3 finds 40 … 79 of run a


def test_half_of_an_even_number_of_monitors_is_no_majority(root: DataRoot) -> None:
    got = robust_hard_set(Warehouse(root), _scores(), thresholds={"m1": 0.5, "m3": 0.4},
                          logical_scenario=SCENARIO, splits=SPLITS).to_pylist()
    unsafe = {(r["scenario_id"], r["frame"]) for r in got if r["label"] == 1}
    assert unsafe == {("a", f) for f in range(20, 40)}  # 40 … 79: missed by m1 alone


def test_frame_mask_marks_the_windows_of_the_selected_frames(root: DataRoot) -> None:
    got = robust_hard_set(Warehouse(root), _scores(), thresholds=THRESHOLDS,
                          logical_scenario=SCENARIO, splits=SPLITS)
    windows = load_windows(root, ["a", "b", "c"], context_len=1)
    mask = frame_mask(got, windows)
    unsafe = mask & (windows.label == 1)
    assert int(unsafe.sum()) == 40 and int((mask & (windows.label == 0)).sum()) == 20 + 20 + 99
    assert set(np.asarray(windows.scenario_id)[unsafe].tolist()) == {"a"}


def test_no_monitor_is_refused(root: DataRoot) -> None:
    with pytest.raises(ValueError, match="at least one"):
        robust_hard_set(Warehouse(root), _scores(), thresholds={}, logical_scenario=SCENARIO)
