"""A regime's curves summarised: per strategy and budget the mean with its CI, the area under
the AUPRC-vs-budget curve, the budget Uniform needs to match each strategy (its sample
efficiency), and each as a paired difference with Uniform over the seeds.

* The curve is a metric (default: Test Set AUPRC of the monitor trained from scratch) at the
  initial budget (G_0, the same for every strategy at a seed) and at each checkpoint.
* Its area is the trapezoid over log2(budget) from the initial budget to the last checkpoint
  every strategy reaches, divided by that width: the curve's mean height on a log-budget axis,
  in the metric's units. Paired with Uniform's seed by seed (`compare_paired`: BCa bootstrap CI
  of the mean difference, Wilcoxon signed-rank p).
* Sample efficiency: the budget at which Uniform's mean curve (interpolated linearly in
  log2 budget, over its checkpoints up to ×16) first reaches a strategy's mean final figure,
  divided by the strategy's final budget. ≥ 1.5 means the strategy needed at most 2/3 of
  Uniform's runs for the same figure. A strategy above Uniform's last point is censored
  ("> factor"). Its CI comes from a bootstrap over seeds (both curves resampled by the same
  seeds), 2.5 and 97.5 percentiles.
* What the seeds could detect (`power.py`): per strategy, the paired minimum detectable effect
  against Uniform on the area and at each checkpoint.
* The oracle against each of its controls (`oracle.py`): the paired difference of their
  areas and final figures — against its uniform-only control (`*_vs_control`) what choosing
  the kind of run adds to a best-of-k choice of runs, against its best-of-k-training-seeds
  control (`*_vs_seeds`) what choosing runs adds to picking the luckiest training seed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from evoeye.evaluation.stats import compare_paired, mean_ci
from evoeye.results.efficiency.config import ORACLE, ORACLE_SEEDS, ORACLE_UNIFORM, REFERENCE
from evoeye.results.efficiency.power import detectable

N_BOOT = 2000
VERSUS = {ORACLE_UNIFORM: "control", ORACLE_SEEDS: "seeds"}  # the oracle's controls' key suffix
CURVE_METRIC = ("test", "auprc")


def figure(curve: dict, budget: int, kind: str = "scratch",
           metric: tuple[str, str] = CURVE_METRIC) -> float:
    """One curve's metric at a budget (NaN if absent or undefined)."""
    entry = curve["budgets"].get(str(budget), {}).get(kind)
    value = None if entry is None else entry.get(metric[0], {}).get(metric[1])
    return float("nan") if value is None else float(value)


def matrix(curves: dict[str, dict], budgets: Sequence[int], seeds: Sequence[int],
           kind: str = "scratch", metric: tuple[str, str] = CURVE_METRIC) -> np.ndarray:
    """(seeds, budgets) of one strategy's curves (NaN where a seed or budget is missing)."""
    out = np.full((len(seeds), len(budgets)), np.nan)
    for i, seed in enumerate(seeds):
        curve = curves.get(str(seed))
        if curve is not None:
            out[i] = [figure(curve, b, kind, metric) for b in budgets]
    return out


def area(values: np.ndarray, budgets: Sequence[int]) -> np.ndarray:
    """(seeds,) the mean height of each row over log2(budget) (trapezoid / width)."""
    x = np.log2(np.asarray(budgets, float))
    return np.trapezoid(values, x, axis=-1) / (x[-1] - x[0])


def budget_to_reach(target: float, curve: np.ndarray, budgets: Sequence[int]) -> float:
    """The budget at which a mean curve first reaches `target` (log2-linear between points):
    NaN if it never does; budgets[0] if it starts there."""
    x = np.log2(np.asarray(budgets, float))
    if not np.isfinite(target) or not np.isfinite(curve).all():
        return float("nan")
    if curve[0] >= target:
        return float(budgets[0])
    for j in range(1, len(curve)):
        if curve[j] >= target:
            frac = (target - curve[j - 1]) / (curve[j] - curve[j - 1])
            return float(2 ** (x[j - 1] + frac * (x[j] - x[j - 1])))
    return float("nan")


def efficiency(strategy_final: np.ndarray, reference: np.ndarray, ref_budgets: Sequence[int],
               final_budget: int, rng: np.random.Generator) -> dict:
    """Sample-efficiency factor of a strategy (module doc), with its bootstrap CI; seeds
    whose figures are missing on either side are left out."""
    ok = np.isfinite(strategy_final) & np.isfinite(reference).all(axis=1)
    s, r = strategy_final[ok], reference[ok]
    if len(s) < 2:
        return {"factor": None, "censored": False, "low": None, "high": None, "n": int(len(s))}
    cap = ref_budgets[-1] / final_budget

    def factor(si: np.ndarray, ri: np.ndarray) -> float:
        b = budget_to_reach(float(si.mean()), ri.mean(axis=0), ref_budgets)
        return math.inf if math.isnan(b) else b / final_budget

    point = factor(s, r)
    boots = np.array([factor(s[i], r[i]) for i in
                      (rng.integers(0, len(s), len(s)) for _ in range(N_BOOT))])
    low, high = np.percentile(np.minimum(boots, cap * 2), [2.5, 97.5])
    return {"factor": min(point, cap), "censored": bool(math.isinf(point)),
            "low": float(min(low, cap)), "high": float(min(high, cap)), "n": int(len(s))}


def summarise(curves: dict[str, dict[str, dict]], seeds: Sequence[int], initial_budget: int,
              checkpoints: Sequence[int],
              reference_budgets: Sequence[int], kind: str = "scratch",
              metric: tuple[str, str] = CURVE_METRIC) -> dict:
    """Per strategy: mean ± CI per budget, area, final figure, efficiency; paired with
    Uniform (module doc)."""
    budgets = [initial_budget, *checkpoints]
    ref_budgets = [*budgets, *reference_budgets]
    rows = {name: matrix(c, budgets if name != REFERENCE else ref_budgets, seeds, kind, metric)
            for name, c in curves.items()}
    ref = rows.get(REFERENCE)
    out: dict = {"metric": list(metric), "kind": kind, "budgets": budgets,
                 "reference_budgets": ref_budgets, "strategies": {}}
    rng = np.random.default_rng(0)
    for name, m in rows.items():
        common = m[:, : len(budgets)]
        entry = {"mean": [mean_ci(m[:, j]).to_dict() for j in range(m.shape[1])],
                 "area": mean_ci(area(common, budgets)).to_dict()}
        if name != REFERENCE and ref is not None:
            entry["area_vs_reference"] = compare_paired(
                area(common, budgets), area(ref[:, : len(budgets)], budgets)).to_dict()
            entry["final_vs_reference"] = compare_paired(common[:, -1],
                                                         ref[:, len(budgets) - 1]).to_dict()
            entry["efficiency"] = efficiency(common[:, -1], ref, ref_budgets, budgets[-1], rng)
            entry["detectable"] = {"area": detectable(area(common, budgets),
                                                      area(ref[:, : len(budgets)], budgets)),
                                   **{str(b): detectable(common[:, j], ref[:, j])
                                      for j, b in enumerate(budgets) if j > 0}}
        out["strategies"][name] = entry
    for name, suffix in VERSUS.items():
        if ORACLE in rows and name in rows:
            oracle, control = rows[ORACLE], rows[name]
            out["strategies"][ORACLE][f"area_vs_{suffix}"] = compare_paired(
                area(oracle, budgets), area(control, budgets)).to_dict()
            out["strategies"][ORACLE][f"final_vs_{suffix}"] = compare_paired(
                oracle[:, -1], control[:, -1]).to_dict()
    return out
