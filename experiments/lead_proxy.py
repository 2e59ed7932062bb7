"""The deployment proxy of a trigger, open loop: does it warn in time to act, and how often for
nothing? Computed on a monitor's scores of the validation windows (issue 37).

For a threshold θ, a run's *alarm onsets* are the frames whose score crosses above θ (K = 1:
score > θ, and the run's previous frame at or below θ, or none). A *false alarm* is an onset at
a frame labelled safe (no collision within H, Definition 1; every frame here is before its run's
collision), counted per hour of such safe driving. With `ValRuns.justified` given,
an onset at a justified safe frame (the run comes critically close within H: the supervisor's
*justified* intervention, approximated by the caller) is no false alarm, and those frames are
no safe driving either (the supervisor's false interventions per hour). A colliding run is
*warned* with lead
τ_col − t of the first frame above θ within H of its collision (a score already above θ when
the last H seconds begin gives lead H: the fallback would already be braking).

At a budget b false alarms per hour the threshold is the lowest θ at which no higher θ gives
more than b (onset counts are not monotone in θ: one excursion may split in two above a higher
θ). Reported there: the share of colliding runs warned ≥ 1.0 s and ≥ 1.5 s ahead, the share
warned at all, the median lead of the warned runs. Uncertainty: a bootstrap over runs that
re-chooses the threshold in every resample (the threshold is as noisy as the rest), and, for two
monitors scored on the same windows, the paired bootstrap of their difference.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.metrics import average_precision_score, roc_auc_score

EPS_S = 1e-6  # frame times sit on a float 20 Hz grid
PAUC_MAX_FPR = 1e-3


@dataclass(frozen=True)
class ValRuns:
    """B frames grouped by run (each run's frames consecutive, in time order)."""

    run_start: np.ndarray  # (R,) int64, first row of each run, ascending, run_start[0] == 0
    lead_s: np.ndarray  # (B,) float64, τ_col − t; +inf in a run without a collision
    dt_s: float  # frame period
    horizon_s: float  # H of the labels
    # (B,) bool or None: safe frames an alarm at is no false one (a critical approach within H)
    justified: np.ndarray | None = None

    @property
    def label(self) -> np.ndarray:
        """(B,) bool: a collision within H (Definition 1)."""
        return self.lead_s <= self.horizon_s + EPS_S

    @property
    def run(self) -> np.ndarray:
        """(B,) the run index of each frame."""
        return np.repeat(np.arange(len(self.run_start)),
                         np.diff(np.append(self.run_start, len(self.lead_s))))

    @classmethod
    def of(cls, scenario_id: np.ndarray, t_s: np.ndarray, collision_time_s: dict[str, float],
           horizon_s: float, dt_s: float = 0.05) -> ValRuns:
        """From windows' (scenario_id, t_s) in run order and each colliding run's τ_col."""
        new = np.r_[True, scenario_id[1:] != scenario_id[:-1]] if len(scenario_id) else []
        start = np.flatnonzero(new)
        tau = np.array([collision_time_s.get(s, np.inf) for s in scenario_id[start]])
        lead = np.repeat(tau, np.diff(np.append(start, len(t_s)))) - np.asarray(t_s)
        return cls(start.astype(np.int64), lead, dt_s, horizon_s)


class Proxy:
    """The proxy of one monitor's scores on `runs`, at any run weights (a bootstrap resample)."""

    def __init__(self, scores: np.ndarray, runs: ValRuns):
        s = np.asarray(scores, np.float64)
        if s.shape != runs.lead_s.shape:
            raise ValueError(f"{s.shape} scores for {runs.lead_s.shape} frames")
        self.runs, run, label = runs, runs.run, runs.label
        prev = np.r_[-np.inf, s[:-1]]
        prev[runs.run_start] = -np.inf
        safe = ~label if runs.justified is None else ~label & ~runs.justified
        crossing = safe & (s > prev)  # safe frames where some θ in [prev, s) makes an onset
        self.hi, self.lo, self.fa_run = s[crossing], prev[crossing], run[crossing]
        self.safe_s = np.bincount(run[safe], minlength=len(runs.run_start)) * runs.dt_s
        self.cand = np.unique(np.r_[self.hi, self.lo[np.isfinite(self.lo)]])  # θ candidates
        self._hi_order, self._lo_order = np.argsort(self.hi), np.argsort(self.lo)
        self._hi_at = np.searchsorted(self.hi[self._hi_order], self.cand, side="right")
        self._lo_at = np.searchsorted(self.lo[self._lo_order], self.cand, side="right")
        pos = np.flatnonzero(label)  # within each run in time order
        self.pos_s, self.pos_lead = s[pos], runs.lead_s[pos]
        self.pos_run = run[pos]
        self.pos_start = np.flatnonzero(np.r_[True, self.pos_run[1:] != self.pos_run[:-1]])
        self.colliding = self.pos_run[self.pos_start]  # (C,) run index of each colliding run

    def false_alarms(self, w: np.ndarray) -> np.ndarray:
        """(len(cand),) weighted false-alarm onsets at each candidate θ (score > θ)."""
        def above(values_order: np.ndarray, at: np.ndarray) -> np.ndarray:
            cum = np.r_[0.0, np.cumsum(w[self.fa_run[values_order]])]
            return cum[-1] - cum[at]
        return above(self._hi_order, self._hi_at) - above(self._lo_order, self._lo_at)

    def threshold(self, budget_per_h: float, w: np.ndarray) -> tuple[float, float]:
        """(θ, its false alarms per hour): the lowest θ with no higher θ over the budget."""
        hours = float(w @ self.safe_s) / 3600.0
        rate = self.false_alarms(w) / max(hours, 1e-12)
        ok = np.logical_and.accumulate((rate <= budget_per_h + 1e-12)[::-1])[::-1]
        if len(ok) == 0 or not ok.any():  # no safe frame ever rises: nothing to bound
            return -np.inf, 0.0
        k = int(np.argmax(ok))
        return float(self.cand[k]), float(rate[k])

    def leads(self, theta: float) -> np.ndarray:
        """(C,) lead of each colliding run's first frame above θ within H; 0: not warned."""
        if len(self.pos_s) == 0:
            return np.zeros(0)
        return np.maximum.reduceat(np.where(self.pos_s > theta, self.pos_lead, 0.0),
                                   self.pos_start)

    def at_budget(self, budget_per_h: float, w: np.ndarray | None = None,
                  lead_bars_s: tuple[float, ...] = (1.0, 1.5)) -> dict[str, float]:
        """Threshold, false alarms/h and the warned shares (%) at a budget, runs weighted `w`."""
        w = np.ones(len(self.runs.run_start)) if w is None else w
        theta, rate = self.threshold(budget_per_h, w)
        lead, wc = self.leads(theta), w[self.colliding]
        total = max(float(wc.sum()), 1e-12)
        out = {"threshold": theta, "fa_per_h": rate,
               "warned_pct": 100.0 * float(wc @ (lead > 0)) / total}
        for bar in lead_bars_s:
            out[f"warned_{bar:g}s_pct"] = 100.0 * float(wc @ (lead >= bar - EPS_S)) / total
        warned = lead > 0
        reps = np.repeat(lead[warned], wc[warned].astype(np.int64))
        out["median_lead_s"] = float(np.median(reps)) if len(reps) else float("nan")
        return out


def frame_metrics(scores: np.ndarray, label: np.ndarray) -> dict[str, float]:
    """AUROC, AUPRC and the standardised partial AUROC at FPR ≤ PAUC_MAX_FPR (McClish, as
    sklearn's roc_auc_score(max_fpr=…)), each in %."""
    y = np.asarray(label).astype(int)
    return {"auroc": 100 * roc_auc_score(y, scores),
            "auprc": 100 * average_precision_score(y, scores),
            "pauc": 100 * roc_auc_score(y, scores, max_fpr=PAUC_MAX_FPR)}


def bootstrap_weights(n_runs: int, n_boot: int, seed: int = 0) -> np.ndarray:
    """(n_boot, n_runs) multinomial run counts of resamples with replacement."""
    rng = np.random.default_rng(seed)
    return np.stack([np.bincount(rng.integers(n_runs, size=n_runs), minlength=n_runs)
                     for _ in range(n_boot)]).astype(np.float64)


def proxy_table(scores: dict[str, np.ndarray], runs: ValRuns, *, reference: str,
                budgets: tuple[float, ...] = (1.0, 5.0), n_boot: int = 1000, seed: int = 0,
                level: float = 0.95) -> dict[str, dict]:
    """Per monitor and budget: the point figures, their bootstrap CIs and the paired CI of the
    difference from `reference` (the same resamples for every monitor)."""
    proxies = {name: Proxy(s, runs) for name, s in scores.items()}
    weights = bootstrap_weights(len(runs.run_start), n_boot, seed)
    q = [50 * (1 - level), 50 * (1 + level)]
    table: dict[str, dict] = {}
    for budget in budgets:
        draws = {name: [p.at_budget(budget, w) for w in weights] for name, p in proxies.items()}
        for name, p in proxies.items():
            point = p.at_budget(budget)
            row = {"point": point, "ci": {}, "diff_ci": {}}
            for key in point:
                mine = np.array([d[key] for d in draws[name]])
                ref = np.array([d[key] for d in draws[reference]])
                row["ci"][key] = np.nanpercentile(mine, q).tolist()
                row["diff_ci"][key] = np.nanpercentile(mine - ref, q).tolist()
            table.setdefault(name, {})[f"{budget:g}"] = row
    return table
