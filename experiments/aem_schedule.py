"""How the AEM baseline's validation ranking grows over a training schedule.

    python -m experiments.aem_schedule --root DIR --results docs/results/rq1-S.json \\
        [--recipe v1] [--seed 100] [--set batch_size=32 --set epochs=3] [--at 4,8,12]

Fits the AEM of a recipe (`evoeye.baselines.aem.AEM_RECIPES`, with `--set` overrides of its
fields) on the recorded RQ1 study's training split, at a seed RQ1 does not record, and after the
epochs `--at` (default: every one) prints its AUROC and AUPRC on the validation split, the
optimiser steps taken and the fit's CPU seconds so far (the evaluations left out). The
validation split only: a schedule chosen here is then judged against RQ1's recorded figures by
`experiments.recipe_validation --method aem` on the test split. docs/training.md has what it
showed (the AUROC follows the optimiser steps, not the epochs).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from evoeye.baselines.aem import AEMMonitor, aem_config, train_aem
from evoeye.monitor.card import ranking_metrics
from evoeye.paths import DataRoot
from evoeye.results.config import ResultsConfig
from evoeye.results.study import Study


def parse_set(items: list[str]) -> dict:
    """`name=value` pairs as AEMConfig overrides (values read as JSON, else as text)."""
    out = {}
    for item in items:
        name, _, value = item.partition("=")
        try:
            out[name] = json.loads(value)
        except json.JSONDecodeError:
            out[name] = value
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True)
    ap.add_argument("--results", required=True, help="a docs/results rq1-*.json")
    ap.add_argument("--recipe", default="v1")
    ap.add_argument("--seed", type=int, default=100, help="not one RQ1 records")
    ap.add_argument("--set", action="append", default=[], help="an AEMConfig field=value")
    ap.add_argument("--at", default=None, help="epochs to evaluate after (default: every one)")
    args = ap.parse_args()
    record = json.loads(Path(args.results).read_text(encoding="utf-8"))
    study = Study(DataRoot.resolve(args.root),
                  ResultsConfig.from_dict(record["config"]).rq1_config())
    (scenario,) = study.config.scenarios
    config = aem_config(args.recipe, seed=args.seed, **parse_set(args.set))
    train = study.windows(scenario, "train").windows
    val = study.windows(scenario, "val").windows
    normal = train.label == 0
    at = set(range(1, config.epochs + 1)) if args.at is None else {
        int(e) for e in args.at.split(",")}
    print(f"{scenario}, AEM {config.record()}\n")
    print("| epoch | steps | CPU s (fit so far) | val AUROC | val AUPRC |")
    print("|---:|---:|---:|---:|---:|")
    spent = {"eval": 0.0}
    c0 = time.process_time()

    def after_epoch(epoch: int, steps: int, aem: AEMMonitor) -> None:
        if epoch not in at:
            return
        cpu = time.process_time() - c0 - spent["eval"]  # so far, the evaluations left out
        e0 = time.process_time()
        m = ranking_metrics(aem.errors(val), val.label)  # the score is monotone in the error
        spent["eval"] += time.process_time() - e0
        print(f"| {epoch} | {steps} | {cpu:.0f} | {100 * m['auroc']:.2f} | "
              f"{100 * m['auprc']:.2f} |", flush=True)

    train_aem(train, np.asarray(normal), config, after_epoch=after_epoch)


if __name__ == "__main__":
    main()
