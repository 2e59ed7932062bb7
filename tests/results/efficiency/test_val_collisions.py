"""A validation set enriched with collisions: drawn from the validation batch's own stream, the
same whatever was simulated before, and leaving the false-positive calibration as it was."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from evoeye.batch import plan_uniform, run_batch
from evoeye.log.synthetic import write_synthetic_batch
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.efficiency.data import (
    SETS,
    VAL_FILE,
    batch_name,
    extend_validation,
    val_extra_ids,
)
from evoeye.results.efficiency.runner import sets_fingerprint
from evoeye.results.efficiency.sets import RegimeData, concat_windows, with_unsafe_windows
from evoeye.store import ingest, load_windows

REGIME = "highway-cut-in"


def test_the_validation_set_holds_the_asked_collisions_from_its_own_stream(tmp_path) -> None:
    data = DataRoot.resolve(tmp_path / "regime")
    config = EfficiencyConfig(regimes=(REGIME,), val_runs=4, data_seed=11)
    seed = config.data_seed + SETS.index("val")
    base = run_batch(plan_uniform(REGIME, 4, seed, batch=batch_name("val", config)),
                     data).collisions
    asked = replace(config, val_collisions=base + 2)
    kept = extend_validation(data, REGIME, asked)
    assert len(kept) == 2 and base + len(kept) >= asked.val_collisions
    drawn = json.loads((data.path / VAL_FILE).read_text())["drawn"]
    logged = sorted(p.name.removesuffix(".mcap") for p in
                    data.batch_dir(REGIME, f"val-more-seed{seed}").glob("*.mcap"))
    stream = plan_uniform(REGIME, 4 + drawn, seed)[4:]  # the batch's stream, past the batch
    collided = {r.scenario_id: r.collided for r in run_batch(
        [replace(s, batch=f"val-more-seed{seed}") for s in stream], data).results}
    assert kept == [s.scenario_id for s in stream if collided[s.scenario_id]][:2]  # the first
    assert logged == sorted(i for i, hit in collided.items() if hit)  # only they were logged
    assert val_extra_ids(data, asked) == kept
    logs = sorted(data.path.rglob("*.mcap"))
    fewer = extend_validation(data, REGIME, replace(config, val_collisions=base + 1))
    assert fewer == kept[:1] and sorted(data.path.rglob("*.mcap")) == logs  # nothing new
    with pytest.raises(ValueError, match="prepare the regime's data again"):
        val_extra_ids(data, asked)  # the file now holds the other config's runs
    assert val_extra_ids(data, config) == []


def test_a_stream_without_enough_collisions_is_refused_with_nothing_written(tmp_path) -> None:
    data = DataRoot.resolve(tmp_path / "regime")
    config = EfficiencyConfig(regimes=(REGIME,), val_runs=1, data_seed=11,
                              val_collisions=10_000)
    with pytest.raises(ValueError, match="further validation runs held"):
        _capped(data, config)
    assert not (data.path / VAL_FILE).exists()


def _capped(data: DataRoot, config: EfficiencyConfig) -> list[str]:
    import evoeye.results.efficiency.data as data_module

    real = data_module.VAL_MAX_CHUNKS
    data_module.VAL_MAX_CHUNKS = 2  # two further runs: a short test
    try:
        return extend_validation(data, REGIME, config)
    finally:
        data_module.VAL_MAX_CHUNKS = real


def test_further_unsafe_windows_leave_the_calibration_as_it_was(tiny_regime, context,
                                                                 tmp_path) -> None:
    """The enriched set's negatives are the batch's, so the thresholds a monitor gets for a
    target FPR are the batch's; whole colliding runs would add negatives, and move them."""
    _, data = tiny_regime
    more = [f"{batch_name('test', context.config)}-{i:02d}" for i in (0, 2, 4)]  # collided
    (data.path / VAL_FILE).write_text(json.dumps({
        "val_runs": context.config.val_runs, "val_collisions": 7,
        "seed": context.config.data_seed + SETS.index("val"), "scenario_ids": more}))
    try:
        enriched = RegimeData.load(data, replace(context.config, val_collisions=7))
    finally:
        (data.path / VAL_FILE).unlink()
    val, big = context.learner.val, enriched.sets["val"]
    assert big.label.sum() > val.label.sum() and (big.label == 0).sum() == (val.label == 0).sum()
    assert set(big.scenario_id) == set(val.scenario_id) | set(more)
    assert sets_fingerprint(enriched) != context.fingerprint
    monitor = context.learner.scratch(context.bank.windows(context.bank.pool.scenario_id[:20]),
                                      3)
    base, plus = monitor.score(val), monitor.score(big)
    assert np.array_equal(plus[big.label == 0], base[val.label == 0])
    before, after = calibrate_on_validation(base, val), calibrate_on_validation(plus, big)
    assert after.by_fpr == before.by_fpr and after.realised_fpr == before.realised_fpr
    # colliding runs long enough to have frames before the horizon: negatives of their own
    other = DataRoot.resolve(tmp_path / "long")
    write_synthetic_batch(other, "long", 6, first_seed=500, n_frames=100, collision_frame=80)
    ingest(other)
    long = load_windows(other, [f"long-{i:02d}" for i in (0, 2, 4)], horizon_s=val.horizon_s)
    assert (long.label == 0).any() and (long.label == 1).any()
    whole = concat_windows([val, long])  # whole colliding runs: their negatives too
    moved = calibrate_on_validation(monitor.score(whole), whole)
    assert moved.by_fpr != before.by_fpr
    unsafe = with_unsafe_windows(val, long)  # their unsafe windows only: as before
    assert calibrate_on_validation(monitor.score(unsafe), unsafe).by_fpr == before.by_fpr
