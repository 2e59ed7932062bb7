"""Collision-time spread and the clock-only AUROC on synthetic labels."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.evaluation.audit.timing import clock_auroc, collision_times, histogram_lines

RUNS, FRAMES = 40, 200  # 10 s runs at 20 Hz


def _frames() -> tuple[np.ndarray, np.ndarray]:
    t = np.tile(np.arange(FRAMES) / 20.0, RUNS)
    return t, np.repeat(np.arange(RUNS), FRAMES)


def test_collision_times_quantiles_and_fullest_bin() -> None:
    ct = collision_times(np.array([1.2, 1.5, 1.9, 2.1, 7.5]))
    assert ct.n == 5 and ct.counts == (0, 3, 1, 0, 0, 0, 0, 1)
    assert ct.quantiles_s["q50"] == pytest.approx(1.9)
    assert ct.quantiles_s["q0"] == 1.2 and ct.quantiles_s["q100"] == 7.5
    assert (ct.top_bin_start_s, ct.top_bin_share) == (1.0, pytest.approx(0.6))
    lines = histogram_lines(ct)
    assert len(lines) == 8 and lines[1].endswith(" 3") and "█" not in lines[0]
    assert collision_times(np.array([])) is None


def test_labels_given_away_by_the_clock_score_high() -> None:
    t, runs = _frames()
    early = (t < 2.0).astype(int)  # "earlier = riskier" is exactly right
    clock = clock_auroc(t, early, runs)
    assert clock.earlier_riskier == pytest.approx(1.0)
    assert clock.headline == pytest.approx(1.0)
    middle = ((t > 4.0) & (t < 6.0)).astype(int)  # no monotone score, but the model finds it
    clock = clock_auroc(t, middle, runs)
    assert clock.best_direction < 0.75
    assert clock.model > 0.95 and clock.headline == clock.model


def test_labels_independent_of_time_score_near_chance() -> None:
    t, runs = _frames()
    rng = np.random.default_rng(0)
    noise = (rng.random(len(t)) < 0.1).astype(int)
    clock = clock_auroc(t, noise, runs)
    assert clock.frames == RUNS * FRAMES and clock.runs == RUNS
    assert abs(clock.earlier_riskier - 0.5) < 0.05
    assert clock.headline < 0.6


def test_one_label_class_has_no_auroc() -> None:
    t, runs = _frames()
    clock = clock_auroc(t, np.zeros_like(runs), runs)
    assert clock.headline is None and clock.model is None
