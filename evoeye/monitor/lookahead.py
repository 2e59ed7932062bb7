"""Training aimed at warning in time to act (issue 37): which windows train, which epoch is kept.

A monitor used as the trigger of a fallback runs at a threshold above nearly every safe frame
(≤ 1 false intervention an hour), and is worth something only if it crosses it while braking
still helps. Two options of a recipe aim its training there; both default to what every
earlier recipe did:

* `TrainParams.min_lead_s` — the unsafe windows closer to their collision than this do not
  train (`preventable_windows`): the last fraction of a second before contact is the easiest
  positive and a useless alarm (the ADS's own emergency braking fires then), and fitting it
  pulls the scores of the earlier, harder positives under the threshold's shadow. They still
  count in every metric and calibration: only the training set changes.
* `TrainParams.select_on` — the early-stopping criterion on the validation windows: "auprc"
  (every earlier recipe) or "pauc", the standardised partial AUROC at FPR ≤ PAUC_MAX_FPR
  (McClish, as sklearn's `roc_auc_score(max_fpr=…)`), which weighs only the strict-threshold
  end of the ranking a trigger runs at.

Both read only the windows' labels and times (the collision time of a run is the frame after
its last eligible one: `collision_lead_s`), never anything a monitor sees at run time.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from sklearn.metrics import average_precision_score, roc_auc_score

from evoeye.criticality import Criticality, frame_risk
from evoeye.log import read_run
from evoeye.log.channels import TOPICS, ground_truth_scene
from evoeye.monitor.recipes import NEAR_MISSES, SELECTIONS
from evoeye.paths import DataRoot
from evoeye.store.catalog import Warehouse
from evoeye.store.features import CONTROL_FEATURES
from evoeye.store.windows import Windows

PAUC_MAX_FPR = 1e-3
# beyond the ADS's 3.5 m/s² comfort limit: its emergency braking (the supervisor's critical
# required deceleration is 4 m/s² too)
NEAR_MISS_DECEL_MPS2 = 4.0
EGO_ACCEL = CONTROL_FEATURES.index("ego_accel_mps2")
LEAD_EPS_S = 1e-6  # frame times sit on a float 20 Hz grid


def collision_lead_s(windows: Windows) -> np.ndarray:
    """(B,) τ_col − t of each window, +inf in a run without a collision. Windows hold a run's
    eligible frames, consecutive and in time order, up to the frame before its collision, so
    τ_col is the run's last window time plus one frame period (that of its last two frames;
    a run of one window: one 20 Hz period). A run is colliding iff it has an unsafe window."""
    n = len(windows)
    if n == 0:
        return np.zeros(0)
    start, stop = windows.run_bounds()
    end = stop - 1  # last row of each run
    t = windows.t_s
    period = np.where(end > start, t[end] - t[np.maximum(end - 1, 0)], 0.05)
    collided = np.maximum.reduceat(windows.label.astype(np.int8), start) > 0
    tau = np.where(collided, t[end] + period, np.inf)
    return np.repeat(tau, end - start + 1) - t


def preventable_windows(train: Windows, min_lead_s: float) -> Windows:
    """`train` without its unsafe windows closer than `min_lead_s` to their collision (all of
    them when `min_lead_s` is 0)."""
    if min_lead_s <= 0:
        return train
    late = (train.label == 1) & (collision_lead_s(train) < min_lead_s - LEAD_EPS_S)
    return train.subset(np.flatnonzero(~late))


def near_miss_windows(windows: Windows, decel_mps2: float = NEAR_MISS_DECEL_MPS2) -> np.ndarray:
    """(B,) bool: safe windows (label 0) within H of which — the window's frame included — the
    ego brakes harder than `decel_mps2` by its own localization: an emergency the run came
    through without a collision. Labels only: it reads the future of the run."""
    n = len(windows)
    out = np.zeros(n, bool)
    if n == 0:
        return out
    accel = windows.features.control[windows.context[:, -1], EGO_ACCEL]  # (B,) at each frame
    for lo, hi in zip(*windows.run_bounds(), strict=True):
        t = windows.t_s[lo:hi]
        hard = np.flatnonzero(accel[lo:hi] < -decel_mps2)  # frames braking that hard
        if len(hard) == 0:
            continue
        # the next such frame at or after each frame, and whether it comes within H
        nxt = hard[np.minimum(np.searchsorted(hard, np.arange(hi - lo)), len(hard) - 1)]
        ahead = (nxt >= np.arange(hi - lo)) & (t[nxt] - t <= windows.horizon_s + LEAD_EPS_S)
        out[lo:hi] = ahead
    return out & (windows.label == 0)


def training_windows(train: Windows, min_lead_s: float = 0.0, near_misses: str = "safe"
                     ) -> Windows:
    """The windows a recipe trains on: without the unsafe ones closer than `min_lead_s` to
    their collision (`preventable_windows`), and the near misses (`near_miss_windows`) kept
    safe (Definition 1), left out ("ignored") or trained as unsafe."""
    if near_misses not in NEAR_MISSES:
        raise ValueError(f"unknown near_misses {near_misses!r}; known: {list(NEAR_MISSES)}")
    if near_misses != "safe":
        near = near_miss_windows(train)
        if near_misses == "unsafe":
            train = replace(train, label=np.where(near, 1, train.label).astype(np.int8))
        else:
            train = train.subset(np.flatnonzero(~near))
    return preventable_windows(train, min_lead_s)


def selection_metric(name: str, scores: np.ndarray, labels: np.ndarray) -> float | None:
    """The validation criterion `name` (SELECTIONS) of these scores; None without both
    classes."""
    y = np.asarray(labels).astype(int)
    if y.min(initial=0) == y.max(initial=0):
        return None
    if name == "auprc":
        return float(average_precision_score(y, scores))
    if name == "pauc":
        return float(roc_auc_score(y, scores, max_fpr=PAUC_MAX_FPR))
    raise ValueError(f"unknown selection {name!r}; known: {list(SELECTIONS)}")


def critical_times(root: DataRoot, scenario_ids: Sequence[str],
                   criticality: Criticality = Criticality()  # noqa: B008 (frozen)
                   ) -> dict[str, np.ndarray]:
    """Each run's critical frames (`evoeye.criticality`: ground-truth TTC-2D or required
    deceleration past its bounds), as their times in s, from every actor's ground truth in the
    run's log. Labels only: a monitor never sees them at run time."""
    ids = sorted(set(scenario_ids))
    con = Warehouse(root).connect()
    try:
        where = con.sql("SELECT scenario_id, logical_scenario, batch FROM scenarios "
                        "WHERE list_contains($ids, scenario_id)", params={"ids": ids}).fetchall()
    finally:
        con.close()
    if missing := sorted(set(ids) - {r[0] for r in where}):
        raise LookupError(f"{len(missing)} run(s) not in the warehouse, e.g. {missing[0]}")
    out = {}
    for sid, scenario, batch in where:
        log = read_run(root.run_log(scenario, batch, sid), [TOPICS.ground_truth])
        scenes = [ground_truth_scene(m) for _, m in log.messages(TOPICS.ground_truth)]
        crit = frame_risk(scenes).critical(criticality)
        out[sid] = np.array([s.t_s for s in scenes])[crit]
    return out


def critical_target(windows: Windows, critical_s: dict[str, np.ndarray]) -> Windows:
    """`windows` with TrainParams.target "critical": a window is unsafe when its run collides
    within H (its label) or has a critical frame (`critical_times`) within [t, t + H] — an
    intervention there is justified, as the supervisor judges one (`justified_frames`)."""
    label = windows.label.astype(bool).copy()
    for lo, hi in zip(*windows.run_bounds(), strict=True):
        times = np.sort(critical_s[str(windows.scenario_id[lo])])
        t = windows.t_s[lo:hi]
        first = np.searchsorted(times, t - LEAD_EPS_S)  # the first critical frame at or after t
        after = np.searchsorted(times, t + windows.horizon_s + LEAD_EPS_S, side="right")
        label[lo:hi] |= after > first
    return replace(windows, label=label.astype(np.int8))
