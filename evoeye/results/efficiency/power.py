"""What a study could have detected: the paired minimum detectable effect (MDE) of each
strategy against Uniform, from the per-seed curves themselves.

A null ("no strategy beats Uniform") says nothing about differences smaller than the MDE: the
true mean paired difference a two-sided paired t-test at α = 0.05 finds with 80 % power over
the seeds run, for the SD of the paired differences those seeds show. The study reports the
Wilcoxon p, whose MDE is ≈ √(π/3) ≈ 1.02× the t-test's for normal differences (its asymptotic
relative efficiency, `evoeye.evaluation.stats`). The MDE at another number of seeds (`n_pairs`)
projects the same SD there: a plan, not a measurement.
"""

from __future__ import annotations

import numpy as np

from evoeye.evaluation.stats import minimum_detectable_effect, sample_sd

POWER = 0.8
ALPHA = 0.05


def detectable(a: np.ndarray, b: np.ndarray, n_pairs: int | None = None) -> dict:
    """{"n", "sd_diff", "correlation", "mde"} of the paired figures a − b (seeds whose figure
    is missing on either side left out); the MDE over `n_pairs` pairs if given, else over the
    pairs measured. None where fewer than 3 pairs define one."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ok = np.isfinite(a) & np.isfinite(b)
    d = a[ok] - b[ok]
    sd = sample_sd(d) if len(d) >= 3 else None
    corr = (float(np.corrcoef(a[ok], b[ok])[0, 1])
            if len(d) >= 3 and a[ok].std() > 0 and b[ok].std() > 0 else None)
    n = n_pairs or len(d)
    mde = (minimum_detectable_effect(n, sd, power=POWER, alpha=ALPHA, test="t")
           if sd is not None else None)
    return {"n": int(len(d)), "n_for_mde": int(n), "sd_diff": sd, "correlation": corr,
            "mde": mde}
