"""Does enriching the validation set with collisions move the false-positive calibration?

    nice -n 15 python -m experiments.val_enrichment --root DIR --val-collisions 100 \\
        [--regime highway-cut-in] [--pool 600] [--test 300] [--val 200] [--train-runs 160] \\
        [--seed 0]

On a data root `ensemble_power` prepared, the validation batch's stream is drawn on until the
set holds `--val-collisions` colliding runs (`data.extend_validation`). One monitor is trained
from scratch on the first `--train-runs` pool runs, early-stopped on the uniform batch, and
calibrated three ways: on the uniform batch, on the batch and the further runs' unsafe windows
(what the study does), and on the batch and the further runs whole (their frames before the
horizon are negatives too). It prints each calibration's thresholds, the FPR each realises on
the Test Set's negatives, and how many of the validation negatives come from colliding runs.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.recipes import recipe_params
from evoeye.monitor.train import fit_windows
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.efficiency.data import extend_validation, regime_root, val_extra_ids
from evoeye.results.efficiency.sets import RegimeData, concat_windows, with_unsafe_windows
from evoeye.store import ingest, load_windows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, required=True)
    parser.add_argument("--regime", default="highway-cut-in")
    parser.add_argument("--pool", type=int, default=600)
    parser.add_argument("--test", type=int, default=300)
    parser.add_argument("--val", type=int, default=200)
    parser.add_argument("--val-collisions", type=int, default=100)
    parser.add_argument("--train-runs", type=int, default=160)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    config = EfficiencyConfig(regimes=(args.regime,), pool_runs=args.pool, test_runs=args.test,
                              val_runs=args.val, checkpoints=(80, 160), reference_checkpoints=(),
                              val_collisions=args.val_collisions)
    data = regime_root(DataRoot.resolve(args.root), args.regime)
    extend_validation(data, args.regime, config, say=print)
    ingest(data)
    sets = RegimeData.load(data, replace(config, val_collisions=0))
    val, test = sets.sets["val"], sets.sets["test"]
    more = load_windows(data, val_extra_ids(data, config), context_len=val.context_len,
                        horizon_s=val.horizon_s)
    train = sets.take(sets.pool.scenario_id[: args.train_runs])
    trained = fit_windows(train, val, replace(recipe_params(config.recipe), seed=args.seed))
    monitor = FusionMonitor(trained.result.net, "check", trained.thresholds)
    test_neg = monitor.score(test)[test.label == 0]
    out = {}
    for name, windows in (("uniform batch", val),
                          ("batch + unsafe windows of further runs",
                           with_unsafe_windows(val, more)),
                          ("batch + further runs whole", concat_windows([val, more]))):
        t = calibrate_on_validation(monitor.score(windows), windows)
        out[name] = {"negatives": int((windows.label == 0).sum()),
                     "positives": int(windows.label.sum()),
                     "thresholds": {str(f): v for f, v in t.by_fpr.items()},
                     "test_fpr": {str(f): float((test_neg > v).mean())
                                  for f, v in t.by_fpr.items()}}
    out["further_runs"] = len(val_extra_ids(data, config))
    out["further_negatives_share_whole"] = float(
        (more.label == 0).sum() / ((val.label == 0).sum() + (more.label == 0).sum()))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
