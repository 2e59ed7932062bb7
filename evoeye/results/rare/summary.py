"""A regime's testing-efficiency figures, from its curves: found, estimated, told apart.

* **Failures found** per 100 simulated runs (and of how many distinct θ): Σ collisions / Σ runs
  over the seeds with a bootstrap interval resampling whole seeds (`rate_ci`); beside Uniform,
  the ratio of the two with a paired bootstrap interval over seeds (seeds resampled jointly),
  and the paired difference of per-seed rates (`compare_paired`) with its minimum detectable effect.
* **Where in the curve** (`by_stretch`): the same rate over each stretch of STRETCH runs (runs
  1–100, 101–200, …) pooled over seeds: a walk that must first climb its levels finds its
  failures late, so its rate over a curve depends on the curve's length.
* **Against a tighter Uniform rate** (`found_pooled`, where the learning side drew a Test
  stream): the same ratio with Uniform's rate pooled over its curves and that stream's uniform
  runs of another seed. A supplement: the claims pair each strategy with Uniform's curves.
* **The failure rate under p.** Each seed's estimate from its own runs: Uniform's share that
  collided (plain Monte Carlo), an importance-sampling strategy's mean of w·y with its runs'
  exact w = p/q (`evoeye.evaluation.failure_rate`), subset simulation's product of its levels'
  conditional probabilities (`subset_estimate`). Other strategies (e.g. AV-Fuzzer) estimate
  nothing. The *reference* P is Uniform's pooled share over all its
  runs (with its Wilson interval): independent of the strategies it judges. Uniform's own
  relative error is then measured about its own mean, which flatters it slightly (hence also
  its exact figure below); a strategy's is measured about an independent P.
  Per strategy: the mean of the seeds' estimates against Uniform's pooled one (an unbiased
  strategy's difference has a CI around 0; `bias`), and the **relative error at equal budget**, the
  root mean square of (estimate − reference) / reference over seeds, with a bootstrap interval;
  beside Uniform the ratio of Uniform's to the strategy's, seeds resampled jointly, the paired
  difference of the seeds' absolute relative errors (Uniform's − the strategy's: > 0 where the
  strategy is closer), and Uniform's exact figure √((1 − P) / (n·P)) at the reference P.
* **Distinct failure mechanisms**: a mechanism is a (class, root cause) pair of a collision
  (`runner.py`); per strategy the distinct ones per seed (mean, paired against Uniform) and
  over all seeds.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from evoeye.evaluation.failure_rate import failure_rate
from evoeye.evaluation.stats import (
    CONFIDENCE,
    compare_paired,
    mean_ci,
    minimum_detectable_effect,
    proportion_ci,
    rate_ci,
)
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.subset import subset_estimate
from evoeye.results.rare.config import ESTIMATING, REFERENCE, RareConfig

PER = 100  # failures per PER simulated runs
STRETCH = 100  # runs per stretch of a curve (`by_stretch`)
SUBSET = "subset"  # estimates from its levels, not from weights
N_RESAMPLES = 10_000


def weights(curve: dict) -> np.ndarray:
    """(n,) p/q of each run (`Records.importance_ratio`: 1 where the run was drawn from p)."""
    def column(values: list) -> np.ndarray:
        return np.array([np.nan if v is None else v for v in values], float)

    n = len(curve["log_q"])
    return Records(np.zeros((n, 0)), np.full(n, np.nan), log_q=column(curve["log_q"]),
                   log_p=column(curve["log_p"])).importance_ratio()


def mechanisms(curve: dict) -> Counter[str]:
    """Collisions per mechanism "class / cause" of one curve."""
    return Counter(f"{r['mechanism']} / {r['cause'] or 'unexplained'}"
                   for r in curve["runs"] if r["collided"])


def _seeds(curves: dict[str, dict]) -> list[str]:
    return sorted(curves, key=int)


def _hits(curve: dict) -> np.ndarray:
    return np.array([r["collided"] for r in curve["runs"]], bool)


def _boot(seeds: int, statistic, seed: int = 0) -> tuple[float | None, float | None]:
    """Percentile interval of statistic(idx) over joint resamples of the seeds. A resample
    where it is undefined (a zero denominator: non-finite) counts as +inf, so the upper end is
    None when more than the tail share of resamples leave it undefined."""
    rng = np.random.default_rng(seed)
    return _percentiles(np.array([statistic(rng.integers(0, seeds, seeds))
                                  for _ in range(N_RESAMPLES)]))


def _percentiles(values: np.ndarray) -> tuple[float | None, float | None]:
    """The CONFIDENCE percentile interval of N_RESAMPLES resampled values, an undefined value
    (non-finite) counting as +inf: an end past the defined ones is None."""
    values = np.sort(np.where(np.isfinite(values), values, np.inf))
    tail = (1.0 - CONFIDENCE) / 2
    low = values[int(math.floor(tail * N_RESAMPLES))]
    high = values[int(math.ceil((1.0 - tail) * N_RESAMPLES)) - 1]
    return (float(low) if math.isfinite(low) else None), \
        (float(high) if math.isfinite(high) else None)


def found(curves: dict[str, dict[str, dict]]) -> dict[str, dict]:
    """Failures found per PER runs, per strategy, and against Uniform (module doc)."""
    out = {}
    counts = {name: {s: (int(_hits(c).sum()), len(c["runs"])) for s, c in seeds.items()}
              for name, seeds in curves.items()}
    for name, rows in counts.items():
        events, runs = zip(*rows.values(), strict=True)
        ci = rate_ci(list(events), list(runs)).to_dict()
        out[name] = {"seeds": len(rows), "runs": int(sum(runs)), "collisions": int(sum(events)),
                     "distinct_x": sum(_distinct_x(c) for c in curves[name].values()),
                     "by_stretch": by_stretch(curves[name].values()),
                     "per_100": {k: (v * PER if isinstance(v, float) and k in
                                     ("value", "low", "high") else v) for k, v in ci.items()}}
    ref = counts.get(REFERENCE)
    for name, rows in counts.items():
        common = [s for s in rows if ref and s in ref]
        if name == REFERENCE or len(common) < 2:
            continue
        a = np.array([rows[s] for s in common], float)  # (S, 2): hits, runs
        b = np.array([ref[s] for s in common], float)

        def ratio(idx: np.ndarray, a=a, b=b) -> float:
            mine, theirs = a[idx, 0].sum() / a[idx, 1].sum(), b[idx, 0].sum() / b[idx, 1].sum()
            return mine / theirs if theirs else math.inf

        paired = compare_paired(PER * a[:, 0] / a[:, 1], PER * b[:, 0] / b[:, 1]).to_dict()
        low, high = _boot(len(common), ratio)
        point = ratio(np.arange(len(common)))
        out[name]["vs_reference"] = {
            "ratio": point if math.isfinite(point) else None, "ratio_low": low,
            "ratio_high": high, "paired": paired,
            "mde_per_100": minimum_detectable_effect(len(common), paired["sd_diff"])
            if paired["sd_diff"] else None}
    return out


def by_stretch(curves, stretch: int = STRETCH) -> list[float]:
    """Collisions per PER runs over each stretch of `stretch` runs of the curves, pooled over
    them (the last stretch as long as the longest curve reaches)."""
    hits = [_hits(c) for c in curves]
    out = []
    for start in range(0, max((len(h) for h in hits), default=0), stretch):
        parts = [h[start:start + stretch] for h in hits]
        runs = sum(len(p) for p in parts)
        out.append(PER * sum(int(p.sum()) for p in parts) / runs)
    return out


def _distinct_x(curve: dict) -> int:
    """The distinct θ among a curve's collisions (a walk that parks on a failure repeats it)."""
    return len({tuple(x) for x, hit in zip(curve["x"], _hits(curve), strict=True) if hit})


def found_pooled(curves: dict[str, dict[str, dict]], runs: int, collisions: int) -> dict:
    """Failures found against a tighter Uniform rate: Uniform's curves pooled with `runs`
    more uniform runs of another seed holding `collisions` (the learning side's Test stream: its
    batch and the runs drawn past it). Per strategy the ratio of its rate to the pooled one,
    with a percentile interval: the seeds its curves share with Uniform's resampled jointly,
    the stream's collisions redrawn binomially. A supplement to `found`: no claim is checked on
    it."""
    ref = curves.get(REFERENCE)
    if not ref or runs <= 0:
        return {}
    hits, total = sum(int(_hits(c).sum()) for c in ref.values()) + collisions, \
        sum(len(c["runs"]) for c in ref.values()) + runs
    wilson = proportion_ci(hits, total)
    out: dict = {"reference": {"runs": total, "collisions": hits, "stream_runs": runs,
                               "stream_collisions": collisions, "value": wilson.value,
                               "low": wilson.low, "high": wilson.high}}
    rng = np.random.default_rng(0)
    stream = rng.binomial(runs, collisions / runs, N_RESAMPLES)
    for name, seeds in curves.items():
        common = [s for s in _seeds(seeds) if s in ref]
        if name == REFERENCE or len(common) < 2:
            continue
        a = np.array([(_hits(seeds[s]).sum(), len(seeds[s]["runs"])) for s in common], float)
        u = np.array([(_hits(ref[s]).sum(), len(ref[s]["runs"])) for s in common], float)
        idx = rng.integers(0, len(common), (N_RESAMPLES, len(common)))
        mine = a[idx, 0].sum(axis=1) / a[idx, 1].sum(axis=1)
        pooled = (u[idx, 0].sum(axis=1) + stream) / (u[idx, 1].sum(axis=1) + runs)
        with np.errstate(divide="ignore", invalid="ignore"):
            low, high = _percentiles(np.where(pooled > 0, mine / pooled, np.inf))
        point = (a[:, 0].sum() / a[:, 1].sum()) / (hits / total) if hits else math.inf
        out[name] = {"ratio": point if math.isfinite(point) else None, "low": low, "high": high}
    return out


def bias(values: np.ndarray, hits: int, runs: int) -> dict:
    """The strategy's mean estimate over seeds − Uniform's pooled share, with the MOVER
    interval (Zou & Donner 2008): each side's own interval combined — the strategy's percentile
    bootstrap over seeds (its estimates are skewed: most seeds of a rare regime see no failure)
    and Uniform's Wilson interval, which stays honest at a handful of collisions or none (a
    normal interval for Uniform's share has no width at 0 and too little at 1 or 2)."""
    u = proportion_ci(hits, runs)
    v = np.asarray(values, float)
    if len(v) < 2 or u.value is None:
        return {"diff": None, "low": None, "high": None}
    mean = float(v.mean())
    low, high = _boot(len(v), lambda idx: float(v[idx].mean()))
    diff = mean - u.value
    return {"diff": diff, "low": diff - math.hypot(mean - low, u.high - u.value),
            "high": diff + math.hypot(high - mean, u.value - u.low)}


def estimate(name: str, curve: dict, batch: int) -> float:
    """One curve's estimate of the failure rate under p (module doc); `batch`: the runs
    between two adaptations (subset simulation's chains)."""
    if name == SUBSET:
        return subset_estimate([r["fitness"] for r in curve["runs"]], _hits(curve), batch)
    return failure_rate(_hits(curve), weights(curve)).value or 0.0


def estimates(curves: dict[str, dict[str, dict]], runs: int, batch: int) -> dict[str, dict]:
    """Per estimating strategy: its seeds' estimates, bias against Uniform's pooled estimate
    and relative error at equal budget about the reference; beside Uniform, the ratio of the
    relative errors (module doc)."""
    per = {name: {s: estimate(name, c, batch) for s, c in seeds.items()}
           for name, seeds in curves.items() if name in ESTIMATING}
    if REFERENCE not in per:
        return {}
    uniform_hits = sum(int(_hits(c).sum()) for c in curves[REFERENCE].values())
    uniform_runs = sum(len(c["runs"]) for c in curves[REFERENCE].values())
    pooled = {name: float(np.mean(list(values.values()))) for name, values in per.items()}
    if not uniform_hits:
        return {"reference": None}
    # the reference is Uniform's pooled share: plain Monte Carlo over all its runs, independent
    # of every other strategy (an inverse-variance mean with an importance-sampling estimator
    # whose seeds mostly saw no failure would trust its near-zero sample variance, and collapse
    # onto it)
    ref = uniform_hits / uniform_runs
    wilson = proportion_ci(uniform_hits, uniform_runs)
    out: dict = {"reference": {"value": ref, "low": wilson.low, "high": wilson.high,
                               "se": math.sqrt(ref * (1 - ref) / uniform_runs),
                               "uniform_pooled": ref,
                               "uniform_runs": uniform_runs, "uniform_collisions": uniform_hits,
                               "uniform_exact_relative_error":
                                   math.sqrt((1 - ref) / (runs * ref))}}
    seeds_u = per[REFERENCE]
    for name, values in per.items():
        v = np.array([values[s] for s in _seeds(values)])
        rel = (v - ref) / ref if ref else np.full(len(v), np.nan)

        def rmse(idx: np.ndarray, rel=rel) -> float:
            return float(np.sqrt(np.mean(rel[idx] ** 2)))

        m = mean_ci(v)
        low, high = _boot(len(v), rmse)
        row = {"seeds": len(v), "per_seed": {s: values[s] for s in _seeds(values)},
               "mean": m.mean, "mean_low": m.low, "mean_high": m.high,
               "pooled": pooled[name], "relative_error": rmse(np.arange(len(v))),
               "relative_error_low": low, "relative_error_high": high,
               "spread": float(v.std(ddof=1) / v.mean()) if len(v) > 1 and v.mean() else None}
        if name != REFERENCE:
            row["bias_vs_uniform"] = bias(v, uniform_hits, uniform_runs)
            common = [s for s in _seeds(values) if s in seeds_u]
            a = np.array([values[s] for s in common])
            b = np.array([seeds_u[s] for s in common])

            def ratio(idx: np.ndarray, a=a, b=b) -> float:
                mine = np.sqrt(np.mean(((a[idx] - ref) / ref) ** 2))
                theirs = np.sqrt(np.mean(((b[idx] - ref) / ref) ** 2))
                return float(theirs / mine) if mine else math.inf

            low, high = _boot(len(common), ratio)
            point = ratio(np.arange(len(common)))
            row["error_ratio"] = {"value": point if math.isfinite(point) else None,
                                  "low": low, "high": high}
            # per seed: how much closer to the reference than Uniform's at the same seed
            row["paired_abs_error"] = compare_paired(np.abs(b - ref) / ref,
                                                     np.abs(a - ref) / ref).to_dict()
        out[name] = row
    return out


def distinct(curves: dict[str, dict[str, dict]]) -> dict[str, dict]:
    """Distinct mechanisms per strategy: per seed (mean, paired against Uniform) and over all
    seeds, with each mechanism's collisions."""
    per = {name: {s: mechanisms(c) for s, c in seeds.items()} for name, seeds in curves.items()}
    out = {}
    for name, rows in per.items():
        total: Counter[str] = Counter()
        for c in rows.values():
            total.update(c)
        m = mean_ci([len(c) for c in rows.values()])
        out[name] = {"per_seed": m.mean, "per_seed_low": m.low, "per_seed_high": m.high,
                     "total": len(total), "by_mechanism": dict(total.most_common()),
                     "classes": len({k.split(" / ")[0] for k in total})}
        if name != REFERENCE and REFERENCE in per:
            common = [s for s in _seeds(rows) if s in per[REFERENCE]]
            out[name]["vs_reference"] = compare_paired(
                [len(rows[s]) for s in common], [len(per[REFERENCE][s]) for s in common]
            ).to_dict()
    return out


def summarise(curves: dict[str, dict[str, dict]], config: RareConfig) -> dict:
    """Every figure of one regime (module doc)."""
    if not curves:
        return {"found": {}, "estimates": {}, "distinct": {}}
    return {"found": found(curves), "estimates": estimates(curves, config.runs, config.batch),
            "distinct": distinct(curves)}
