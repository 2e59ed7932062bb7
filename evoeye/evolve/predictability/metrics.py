"""The predictability figures, pure: cross-validated forests on θ, outcome flips, the verdict."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.stats import spearmanr
from sklearn.ensemble import RandomForestClassifier, RandomForestRegressor
from sklearn.metrics import r2_score, roc_auc_score
from sklearn.model_selection import KFold, StratifiedKFold, cross_val_predict

FOLDS = 5
N_TREES = 200
MIN_SAMPLES_LEAF = 3
MIN_RUNS = 20  # fewer runs (or, for AUROC, fewer than FOLDS of either class): no figure
# A cross-validated Spearman ρ below RHO_MIN, or with p ≥ P_MAX, predicts nothing: out-of-fold
# predictions of pure noise (200 runs, 10 dims) gave ρ with SD 0.085 over 30 draws, as far out
# as ±0.19, and spearmanr's p, which treats the folds' predictions as independent, is too small.
RHO_MIN = 0.2
P_MAX = 0.05
# ... and a significant ρ whose out-of-fold R² stays below R2_MIN ranks a little but explains
# almost none of the error: a strategy steering by it gains little (S1's default ADS: ρ 0.27,
# R² 0.04, and no strategy above Uniform).
R2_MIN = 0.1
AUROC_MIN = 0.6
BOOTSTRAP = 1000  # resamples of the runs for the AUROC's 95 % interval


@dataclass(frozen=True)
class Classified:
    """Cross-validated prediction of a binary outcome from θ."""

    runs: int
    positives: int
    auroc: float | None  # None: too few runs or too few of one class
    auroc_ci: tuple[float, float] | None = None  # 95 %, bootstrap over the runs
    fold_aurocs: tuple[float, ...] = ()  # each fold's AUROC on its held-out runs


@dataclass(frozen=True)
class Regressed:
    """Cross-validated prediction of a per-run value from θ."""

    runs: int
    r2: float | None
    spearman: float | None
    spearman_p: float | None

    @property
    def predictive(self) -> bool:
        """A positive rank correlation, significant: θ tells high values from low."""
        return (self.spearman is not None and self.spearman >= RHO_MIN
                and self.spearman_p is not None and self.spearman_p < P_MAX)


@dataclass(frozen=True)
class Flips:
    """How often re-simulating a θ with a new seed changes whether it collides."""

    thetas: int
    seeds: int  # new seeds per θ
    flip_share: float  # re-simulations whose outcome differs from the run's own
    ambiguous_share: float  # θ whose outcomes (its own and the new) are not all equal
    collision_share: float  # collisions among the re-simulations


def _folds(seed: int) -> StratifiedKFold:
    return StratifiedKFold(FOLDS, shuffle=True, random_state=seed)


def cv_probabilities(u: np.ndarray, y: np.ndarray, seed: int) -> np.ndarray | None:
    """Out-of-fold collision probabilities (n,) of a random forest on u (n, dim) → y (n,);
    None with too few runs or too few of one class."""
    y = np.asarray(y, dtype=bool)
    if len(y) < MIN_RUNS or min(int(y.sum()), int((~y).sum())) < FOLDS:
        return None
    model = RandomForestClassifier(n_estimators=N_TREES, min_samples_leaf=MIN_SAMPLES_LEAF,
                                   random_state=seed, n_jobs=1)
    return cross_val_predict(model, u, y, cv=_folds(seed), method="predict_proba")[:, 1]


def auroc_interval(y: np.ndarray, p: np.ndarray, seed: int) -> tuple[float, float]:
    """95 % percentile interval of the AUROC of p for y over BOOTSTRAP resamples of the runs
    (resamples holding one class only are skipped)."""
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(y), size=(BOOTSTRAP, len(y)))
    both = [d for d in draws if 0 < y[d].sum() < len(d)]
    aurocs = [roc_auc_score(y[d], p[d]) for d in both]
    low, high = np.percentile(aurocs, [2.5, 97.5])
    return float(low), float(high)


def classified(y: np.ndarray, p: np.ndarray | None, seed: int = 0) -> Classified:
    """The AUROC of out-of-fold probabilities p (`cv_probabilities` with `seed`) for outcomes
    y, its bootstrap interval and each fold's."""
    y = np.asarray(y, dtype=bool)
    if p is None:
        return Classified(len(y), int(y.sum()), None)
    folds = tuple(float(roc_auc_score(y[held], p[held]))
                  for _, held in _folds(seed).split(np.zeros(len(y)), y))
    return Classified(len(y), int(y.sum()), float(roc_auc_score(y, p)),
                      auroc_interval(y, p, seed), folds)


def cv_auroc(u: np.ndarray, y: np.ndarray, seed: int) -> Classified:
    """AUROC of out-of-fold collision probabilities of a random forest on u (n, dim) → y (n,)."""
    return classified(y, cv_probabilities(u, y, seed), seed)


def cv_regression(u: np.ndarray, y: np.ndarray, seed: int) -> Regressed:
    """R² and Spearman ρ of out-of-fold predictions of a random forest on u (n, dim) → y (n,);
    runs with a non-finite y are left out."""
    keep = np.isfinite(np.asarray(y, dtype=float))
    u, y = u[keep], np.asarray(y, dtype=float)[keep]
    if len(y) < MIN_RUNS or np.ptp(y) == 0:
        return Regressed(len(y), None, None, None)
    model = RandomForestRegressor(n_estimators=N_TREES, min_samples_leaf=MIN_SAMPLES_LEAF,
                                  random_state=seed, n_jobs=1)
    pred = cross_val_predict(model, u, y, cv=KFold(FOLDS, shuffle=True, random_state=seed))
    rho = spearmanr(pred, y)
    return Regressed(len(y), float(r2_score(y, pred)), float(rho.statistic), float(rho.pvalue))


def flips(own: np.ndarray, again: np.ndarray) -> Flips:
    """Outcome flips of θ re-simulated: `own` (n,) the runs' outcomes, `again` (n, k) theirs
    under k new seeds (1.0 collided, 0.0 not, NaN a re-simulation that failed: left out)."""
    own, again = np.asarray(own, dtype=bool), np.asarray(again, dtype=float)
    if again.ndim != 2 or again.shape[0] != own.shape[0] or again.size == 0:
        raise ValueError(f"need outcomes (n,) and re-simulated (n, k), got {own.shape} and "
                         f"{again.shape}")
    done = np.isfinite(again)
    differs = done & (again != own[:, None])
    return Flips(int(len(own)), int(again.shape[1]), float(differs.sum() / max(done.sum(), 1)),
                 float(differs.any(axis=1).mean()),
                 float(again[done].mean()) if done.any() else float("nan"))


def verdict(collision: Classified, error: Regressed | None, noise: Flips | None = None,
            boundary: Flips | None = None) -> list[str]:
    """What the figures mean for acquisition, one plain sentence each (`noise`: re-runs of θ
    drawn uniformly; `boundary`: of the θ nearest the failure boundary)."""
    lines = []
    if collision.auroc is None:
        lines.append("Too few runs of one outcome to tell whether θ predicts a collision.")
    elif collision.auroc >= AUROC_MIN:
        lines.append(f"θ predicts a run's collision (AUROC {collision.auroc:.2f}): the failure "
                     "boundary is learnable, a boundary-seeking strategy has a signal.")
    else:
        lines.append(f"θ hardly predicts a run's collision (AUROC {collision.auroc:.2f}): "
                     "there is no boundary in θ to seek.")
    if error is None:
        lines.append("No monitor error measured (no monitor, or no run it did not train on).")
    elif error.predictive and (error.r2 is None or error.r2 < R2_MIN):
        lines.append(f"θ predicts the monitor's error only weakly (Spearman {error.spearman:.2f}, "
                     f"p = {error.spearman_p:.2g}, but R² {_r2(error)}): it ranks runs a "
                     "little and explains almost none of the error, so a strategy that chooses "
                     "θ can gain little over Uniform at finding where this monitor errs.")
    elif error.predictive:
        lines.append(f"θ predicts the monitor's error (Spearman {error.spearman:.2f}, "
                     f"p = {error.spearman_p:.2g}, R² {_r2(error)}): a strategy that chooses θ "
                     "can steer toward where the monitor errs.")
    else:
        rho = "–" if error.spearman is None else f"{error.spearman:.2f}"
        lines.append(f"θ does not predict the monitor's error (Spearman {rho}): no strategy "
                     "that chooses θ can beat Uniform at finding where this monitor errs.")
    for flips_of, where in ((noise, "θ drawn uniformly"),
                            (boundary, "the θ nearest the failure boundary")):
        if flips_of is None:
            continue
        share = f"{100 * flips_of.flip_share:.0f} %"
        lines.append(f"Re-simulated with new seeds, {share} of the outcomes of {where} flip "
                     f"({100 * flips_of.ambiguous_share:.0f} % of them are ambiguous)" + (
                         ": there, that much of the outcome is chance no choice of θ removes."
                         if flips_of.flip_share > 0 else ": the outcome is a function of θ."))
    return lines


def _r2(error: Regressed) -> str:
    return "–" if error.r2 is None else f"{error.r2:.2f}"


def as_dict(figure: Classified | Regressed | Flips | None) -> dict | None:
    return None if figure is None else asdict(figure)
