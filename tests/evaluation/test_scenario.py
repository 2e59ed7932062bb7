"""Scenario-level detection with K consecutive alarms, and warning lead times, by hand."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.evaluation.scenario import Runs, consecutive_counts, scenario_metrics
from evoeye.monitor.protocol import Thresholds

RATE_HZ = 20.0
N_FRAMES = 15
# run → (collision frame or None, frames that alarm)
RUNS = {
    "s1": (None, [0, 1, 2]),  # safe, three in a row: a false positive even at K = 3
    "s2": (None, [4, 6, 13, 14]),  # safe, never three in a row; ends on two alarms
    "v1": (10, [0, 3, 4, 8, 9]),  # two in a row twice before the collision
    "v2": (10, [5, 6, 7]),  # three in a row, the third at frame 7 (0.35 s)
}
THRESHOLDS = Thresholds({0.05: 0.5, 0.01: 0.95})


def frames(seed: int = 0):
    ids, frame, t, tau, score = [], [], [], [], []
    for sid, (col, on) in RUNS.items():
        for i in range(N_FRAMES if col is None else col):  # eligible frames, as load_windows
            ids.append(sid)
            frame.append(i)
            t.append(i / RATE_HZ)
            tau.append(np.inf if col is None else col / RATE_HZ)
            score.append(0.9 if i in on else 0.1)
    perm = np.random.default_rng(seed).permutation(len(ids))  # any input order
    arrays = [np.array(a)[perm] for a in (ids, frame, t, tau, score)]
    ids, frame, t, tau, score = arrays
    return Runs.of(ids, frame, t, tau), score


def test_consecutive_counts_restart_at_every_run() -> None:
    alarm = np.array([1, 1, 0, 1, 1, 1, 1, 0], bool)
    assert consecutive_counts(alarm, np.array([0, 4])).tolist() == [1, 2, 0, 1, 1, 2, 3, 0]


def test_k3_needs_three_alarms_before_the_collision() -> None:
    runs, score = frames()
    m = scenario_metrics(score, runs, THRESHOLDS, k=3)
    at = m.at_fpr[0.05]
    # v2 detected; v1 missed (never three in a row before its collision); s1 false positive;
    # s2's last two alarms do not join v1's first one across the run boundary
    assert (at.tp, at.fn, at.fp, at.tn) == (1, 1, 1, 1)
    assert (at.precision, at.recall, at.f1) == pytest.approx((0.5, 0.5, 0.5))
    lead = m.lead_time[0.05]
    assert (lead.detected, lead.violations) == (1, 2)
    assert lead.values_s == pytest.approx([0.5 - 7 / RATE_HZ])  # warned when the 3rd alarms
    assert m.scenarios == 4 and m.violations == 2


def test_k1_warns_at_the_first_alarm() -> None:
    runs, score = frames(seed=1)
    m = scenario_metrics(score, runs, THRESHOLDS, k=1)
    at = m.at_fpr[0.05]
    assert (at.tp, at.fn, at.fp, at.tn) == (2, 0, 2, 0)
    assert m.lead_time[0.05].values_s == pytest.approx([0.5, 0.5 - 5 / RATE_HZ])  # v1, v2
    assert m.lead_time[0.05].median_s == pytest.approx(0.375)
    none = m.at_fpr[0.01]  # threshold 0.95: nothing alarms
    assert (none.tp, none.fp, none.fn, none.tn) == (0, 0, 2, 2)
    assert m.lead_time[0.01].median_s is None


def test_run_scores_rank_runs_as_their_warnings_do() -> None:
    runs, score = frames()
    m = scenario_metrics(score, runs, THRESHOLDS, k=3)
    # held-for-3 scores: s1 0.9, s2 0.1, v1 0.1 (before the collision), v2 0.9
    # -> (v, s) pairs: v1<s1 0, v1=s2 .5, v2=s1 .5, v2>s2 1
    assert m.auroc == pytest.approx(0.5)


def test_false_alarms_count_every_warning_of_the_safe_runs_per_hour() -> None:
    runs, score = frames(seed=2)
    hours = 2 * N_FRAMES / RATE_HZ / 3600  # s1 and s2, every frame eligible
    k3 = scenario_metrics(score, runs, THRESHOLDS, k=3).false_alarms[0.05]
    assert (k3.events, k3.safe_runs, k3.alarmed_runs) == (1, 2, 1)  # s1's 0-2; s2 never 3
    assert k3.safe_h == pytest.approx(hours)
    assert k3.per_h.value == pytest.approx(1 / hours)
    k1 = scenario_metrics(score, runs, THRESHOLDS, k=1).false_alarms[0.05]
    assert (k1.events, k1.alarmed_runs) == (4, 2)  # s1: 0-2 once; s2: 4, 6 and 13-14
    assert k1.per_run == [1, 3]
    quiet = scenario_metrics(score, runs, THRESHOLDS, k=1).false_alarms[0.01]
    assert quiet.events == 0 and quiet.per_h.value == 0.0
    assert quiet.per_h.high == pytest.approx(-np.log(0.05) / hours)  # the Poisson bound


def test_lead_times_name_the_runs_warned_of_and_carry_intervals() -> None:
    runs, score = frames()
    lead = scenario_metrics(score, runs, THRESHOLDS, k=1).lead_time[0.05]
    assert lead.warned_ids == ["v1", "v2"]
    assert (lead.recall.value, lead.recall.n) == (1.0, 2)
    assert lead.recall.low < 0.5 < lead.recall.high == 1.0  # 2 of 2 says little
    d = lead.to_dict()
    assert d["median"]["value"] == pytest.approx(0.375) and d["recall"]["method"] == "wilson"
