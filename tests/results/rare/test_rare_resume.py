"""The rare-failure protocol resumes from its ledger: a re-run simulates nothing and reports the
same figures; a curve whose strategy options change is a new unit."""

from __future__ import annotations

from dataclasses import replace

from evoeye.paths import DataRoot
from evoeye.results.rare.config import RareConfig
from evoeye.results.rare.part import run_rare


def test_a_rerun_reads_every_curve_back_and_changes_nothing(tmp_path):
    root = DataRoot(tmp_path)
    config = RareConfig(regimes=("highway-cut-in:cautious",), seeds=(0, 1), runs=2, batch=1,
                        explain=False)
    first = run_rare(root, config, workers=2)
    assert first["computed"] == 4 and not first["failed"]
    again = run_rare(root, config)
    assert again["computed"] == 0
    assert again["regimes"] == first["regimes"]
    found = first["regimes"]["highway-cut-in:cautious"]["found"]
    assert found["uniform"]["runs"] == 4 and found["ce-is"]["runs"] == 4
    tuned = run_rare(root, replace(config, ce_screen_z=1.0))
    assert tuned["computed"] == 2  # ce-is's two curves; Uniform's are read back
