"""What a study could detect: the paired minimum detectable effect from per-seed figures."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.results.efficiency.power import detectable
from evoeye.results.efficiency.report import detectable_table
from evoeye.results.efficiency.summary import summarise


def test_the_mde_of_a_hand_computed_pairing() -> None:
    # 40 pairs whose differences alternate 0, 2: mean 1, sample SD √(40/39) = 1.01274.
    # (t_0.975;39 + t_0.8;39) · SD / √40 = (2.02269 + 0.85070) · 1.01274 / 6.32456 = 0.4601
    b = np.random.default_rng(3).normal(0.5, 0.2, 40)
    a = b + np.tile([0.0, 2.0], 20)
    d = detectable(a, b)
    assert d["n"] == 40 and d["sd_diff"] == pytest.approx(np.sqrt(40 / 39))
    assert d["mde"] == pytest.approx(0.4601, rel=0.01)
    # the seeds' own spread cancels in the pairing: only the differences count
    assert detectable(a * 1 + 5.0, b + 5.0)["mde"] == pytest.approx(d["mde"])


def test_missing_pairs_are_left_out_and_more_pairs_project_a_smaller_mde() -> None:
    b = np.random.default_rng(4).normal(0.5, 0.2, 12)
    a = b + np.random.default_rng(5).normal(0.0, 0.1, 12)
    a[0], b[1] = np.nan, np.nan
    d = detectable(a, b)
    assert d["n"] == 10
    planned = detectable(a, b, n_pairs=40)
    assert planned["n"] == 10 and planned["n_for_mde"] == 40
    assert planned["mde"] == pytest.approx(d["mde"] / 2, rel=0.15)  # ≈ √(10/40)
    assert detectable(a[:4], b[:4])["mde"] is None  # two pairs left: none defined


def test_summarise_reports_what_each_comparison_could_detect() -> None:
    seeds = list(range(10))
    rng = np.random.default_rng(6)
    base, noise = rng.normal(0.4, 0.1, 10), rng.normal(0.0, 0.05, 10)

    def curve(v: float, budgets) -> dict:
        return {"budgets": {str(b): {"scratch": {"test": {"auprc": v + b / 1000}}}
                            for b in budgets}}

    uniform = {str(s): curve(base[s], [40, 80, 160, 320, 640]) for s in seeds}
    other = {str(s): curve(base[s] + noise[s], [40, 80, 160, 320]) for s in seeds}
    out = summarise({"uniform": uniform, "boundary": other}, seeds, 40, [80, 160, 320], [640])
    det = out["strategies"]["boundary"]["detectable"]
    assert set(det) == {"area", "80", "160", "320"}
    # every budget's difference is the same `noise`, so is its MDE, about its SD
    assert det["320"]["sd_diff"] == pytest.approx(np.std(noise, ddof=1))
    assert det["80"]["mde"] == pytest.approx(det["320"]["mde"])
    assert det["320"]["mde"] == pytest.approx(0.995 * np.std(noise, ddof=1), rel=0.02)
    assert "detectable" not in out["strategies"]["uniform"]
    table = "\n".join(detectable_table(out))
    assert f"| boundary | {100 * det['area']['mde']:.1f} (SD " in table and "n = 10" in table
