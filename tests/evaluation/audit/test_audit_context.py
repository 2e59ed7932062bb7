"""The audit's context-only check on synthetic frames: where the ego is gives labels away or not."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.evaluation.audit.context import context_auroc

RUNS, FRAMES = 30, 100  # 5 s runs at 20 Hz


def _context(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) t, speed, x, y for runs driving north at 10 m/s from a seeded start; run ids."""
    t = np.tile(np.arange(FRAMES) / 20.0, RUNS)
    runs = np.repeat(np.arange(RUNS), FRAMES)
    y0 = rng.uniform(-60.0, -10.0, RUNS)[runs]
    x = np.column_stack([t, np.full_like(t, 10.0), np.zeros_like(t), y0 + 10.0 * t])
    return x, runs


def test_labels_given_away_by_the_place_score_high_and_the_clock_does_not_know() -> None:
    rng = np.random.default_rng(1)
    x, runs = _context(rng)
    near_box = ((x[:, 3] > -5.0) & (x[:, 3] < 5.0)).astype(int)  # the box at y = 0
    ctx = context_auroc(x, near_box, runs)
    assert ctx.frames == RUNS * FRAMES and ctx.runs == RUNS
    assert ctx.unsafe_frames == int(near_box.sum()) > 0
    assert ctx.auroc > 0.97 and ctx.auprc > 0.8
    assert ctx.where_when_auroc > 0.97  # the place alone gives it away: speed is constant


def test_labels_given_away_by_the_ego_speed_need_the_speed() -> None:
    rng = np.random.default_rng(4)
    x, runs = _context(rng)
    x[:, 1] = rng.choice([5.0, 10.0], RUNS)[runs]  # some runs slow, some keep their speed
    fast_near_box = ((x[:, 1] > 7.0) & (x[:, 3] > -5.0) & (x[:, 3] < 5.0)).astype(int)
    ctx = context_auroc(x, fast_near_box, runs)
    assert ctx.auroc > 0.97
    assert ctx.where_when_auroc < ctx.auroc - 0.05  # without the speed, half the box is wrong


def test_labels_independent_of_the_context_score_near_chance() -> None:
    rng = np.random.default_rng(2)
    x, runs = _context(rng)
    noise = (rng.random(len(runs)) < 0.1).astype(int)
    ctx = context_auroc(x, noise, runs)
    assert ctx.auroc == pytest.approx(0.5, abs=0.06)
    assert ctx.where_when_auroc == pytest.approx(0.5, abs=0.06)


def test_one_label_class_has_no_auroc() -> None:
    x, runs = _context(np.random.default_rng(3))
    ctx = context_auroc(x, np.zeros(len(runs), dtype=int), runs)
    assert ctx.auroc is None and ctx.auprc is None and ctx.unsafe_frames == 0
    assert ctx.where_when_auroc is None and ctx.where_when_auprc is None
