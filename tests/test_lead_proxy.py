"""The open-loop deployment proxy of issue 37 (experiments/lead_proxy.py) on hand-made runs."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.lead_proxy import Proxy, ValRuns, proxy_table

DT = 0.05


def two_runs(safe_scores: list[float], collide_scores: list[float]) -> tuple[np.ndarray, ValRuns]:
    """A run without a collision, then one colliding one frame after its last frame."""
    n, m = len(safe_scores), len(collide_scores)
    sid = np.array(["a"] * n + ["b"] * m, dtype=object)
    t = np.r_[np.arange(n), np.arange(m)] * DT
    runs = ValRuns.of(sid, t, {"b": m * DT}, horizon_s=3.0, dt_s=DT)
    return np.array(safe_scores + collide_scores), runs


def test_onsets_count_crossings_not_frames_and_not_unsafe_ones() -> None:
    # safe run: one excursion of 3 frames above 0.5, then another one frame above 0.5
    safe = [0.1, 0.6, 0.7, 0.6, 0.2, 0.9, 0.1]
    # colliding run of 80 frames (4 s): frames 0..19 are safe (lead > 3 s), 20..79 unsafe
    coll = [0.1] * 19 + [0.8] + [0.1] * 30 + [0.95] * 30
    scores, runs = two_runs(safe, coll)
    p = Proxy(scores, runs)
    theta = np.array([0.55, 0.65, 0.75, 0.85, 0.92])
    fa = p.false_alarms(np.ones(2))
    got = [fa[np.searchsorted(p.cand, th, side="right") - 1] for th in theta]
    # 0.55: two excursions of the safe run + the colliding run's safe spike at frame 19
    # 0.65: the 0.7 frame, 0.9 and 0.8; 0.75: 0.9 and 0.8; 0.85: 0.9; 0.92: none
    assert got == [3, 3, 2, 1, 0]
    # the onset at 0.95 (frame 50, lead 1.5 s) is within H: a warning, never a false alarm
    assert p.leads(0.9)[0] == pytest.approx(30 * DT)
    # above the unsafe frames' score: not warned
    assert p.leads(0.95)[0] == 0.0


def test_threshold_is_the_lowest_within_budget_and_counts_safe_hours() -> None:
    safe = [0.1, 0.6, 0.7, 0.6, 0.2, 0.9, 0.1]
    coll = [0.1] * 19 + [0.8] + [0.1] * 30 + [0.95] * 30
    scores, runs = two_runs(safe, coll)
    p = Proxy(scores, runs)
    hours = (7 + 20) * DT / 3600
    theta, rate = p.threshold(1.0 / hours, np.ones(2))  # one false alarm allowed
    assert theta == pytest.approx(0.8) and rate == pytest.approx(1.0 / hours)
    out = p.at_budget(1.0 / hours)
    assert out["warned_pct"] == 100.0 and out["warned_1s_pct"] == 100.0
    assert out["warned_1.5s_pct"] == 100.0 and out["median_lead_s"] == pytest.approx(1.5)
    # a budget of none: above every safe frame's score, 0.9, still under 0.95: warned
    assert p.threshold(0.0, np.ones(2))[0] == pytest.approx(0.9)


def test_a_score_already_high_when_h_begins_warns_with_lead_h() -> None:
    coll = [0.1] * 10 + [0.99] * 70  # rises 3.5 s ahead, stays up
    scores, runs = two_runs([0.1] * 5, coll)
    p = Proxy(scores, runs)
    assert p.leads(0.5)[0] == pytest.approx(3.0)
    fa = p.false_alarms(np.ones(2))
    assert fa[np.searchsorted(p.cand, 0.5, side="right") - 1] == 1  # its onset was unsafe


def test_paired_bootstrap_of_a_monitor_against_itself_is_zero() -> None:
    rng = np.random.default_rng(1)
    sid, t, tau = [], [], {}
    for r in range(30):
        n = 100
        sid += [f"r{r}"] * n
        t += list(np.arange(n) * DT)
        if r % 3 == 0:
            tau[f"r{r}"] = n * DT
    runs = ValRuns.of(np.array(sid, dtype=object), np.array(t), tau, 3.0, DT)
    scores = rng.random(len(sid)) * 0.5 + 0.5 * runs.label
    table = proxy_table({"a": scores, "b": scores.copy()}, runs, reference="a", n_boot=50)
    row = table["b"]["5"]
    assert row["diff_ci"]["warned_1s_pct"] == [0.0, 0.0]
    assert row["ci"]["warned_1s_pct"][0] <= row["point"]["warned_1s_pct"] \
        <= row["ci"]["warned_1s_pct"][1]


def test_justified_safe_frames_are_no_false_alarms_nor_safe_hours() -> None:
    from dataclasses import replace

    safe = [0.1, 0.6, 0.7, 0.6, 0.2, 0.9, 0.1]
    coll = [0.1] * 19 + [0.8] + [0.1] * 30 + [0.95] * 30
    scores, runs = two_runs(safe, coll)
    justified = np.zeros(len(scores), bool)
    justified[5] = True  # the safe run's 0.9 spike came with a critical approach
    p = Proxy(scores, replace(runs, justified=justified))
    fa = p.false_alarms(np.ones(2))
    # at 0.85 the only onset left was that spike: none now; at 0.75 the 0.8 spike remains
    assert fa[np.searchsorted(p.cand, 0.85, side="right") - 1] == 0
    assert fa[np.searchsorted(p.cand, 0.75, side="right") - 1] == 1
    assert p.safe_s.sum() == pytest.approx((7 + 20 - 1) * DT)
