"""A training recipe against the RQ1 figures docs/results recorded, paired over training seeds.

    python -m experiments.recipe_validation --root DIR --results docs/results/rq1-S.json \\
        [--recipe v2] [--method FusionMonitor|aem] [--seeds 0,1,2,3,4,5] [--out FILE.json]

DIR holds the run's RQ1 data regenerated (`evoeye.results.study.prepare_data` with the recorded
config's seeds and sizes: the same seeds give the same runs). The script first checks that it is
the recorded data — every split's runs, violations, frames and unsafe frames, and the TTC rule's
test figures, equal to the recorded ones — then trains the FusionMonitor (or, with `--method
aem`, the AEM baseline) of the recipe at the seeds through the results' own units
(`units.trained_versions`: RQ1's ledger, seeds together; `units.baseline` for the AEM) and
judges each as RQ1 does (`units.test_figures`). It prints, per seed, the recorded and the new
figures, and per metric the paired difference new − recorded: mean, 95 % BCa bootstrap CI and
Wilcoxon p (`evoeye.evaluation.stats.compare_paired`), with the recorded mean's t interval and
whether the new mean lies inside it; and per seed the training's epochs, wall and CPU seconds
(from its card). `--out` keeps all of it as JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from dataclasses import replace
from pathlib import Path

from evoeye.evaluation.stats import compare_paired, mean_ci
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.monitor.inputs import MODULES
from evoeye.monitor.registry import read_card
from evoeye.paths import DataRoot
from evoeye.results import units
from evoeye.results.config import ResultsConfig
from evoeye.results.rq1 import FULL_CONTEXT_LEN, FUSION_LABEL
from evoeye.results.study import Study

METRICS = ("f1@0.05", "f1@0.01", "auroc", "auprc")
RULE = "ttc"  # a rule: no training, so its figures show the data is the recorded data


def check_data(study: Study, scenario: str, recorded: dict) -> None:
    """SystemExit naming the first split or rule figure that differs from the record."""
    data = recorded.get("rq1_data") or recorded["data"]  # RQ1's own data, or the study's
    for split, stats in data["splits"].items():
        have = study.windows(scenario, split).stats()
        want = {k: stats[k] for k in have}
        if have != want:
            raise SystemExit(f"{scenario} {split}: {have} here, {want} recorded")
    rule = units.test_figures(study, scenario, units.baseline(study, scenario, RULE, 0))["test"]
    want = recorded["rq1"]["methods"][RULE]["figures"][0]["test"]
    if {k: rule[k] for k in METRICS} != {k: want[k] for k in METRICS}:
        raise SystemExit(f"{scenario} {RULE}: {rule} here, {want} recorded")
    print(f"{scenario}: the recorded data (split sizes and {RULE}'s test figures equal)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True)
    ap.add_argument("--results", required=True, help="a docs/results rq1-*.json")
    ap.add_argument("--recipe", default="v2")
    ap.add_argument("--method", default=FUSION_LABEL, choices=(FUSION_LABEL, "aem"),
                    help="the recorded method to train again by the recipe")
    ap.add_argument("--seeds", default=None, help="comma list (default: the recorded seeds)")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    record = json.loads(Path(args.results).read_text(encoding="utf-8"))
    config = ResultsConfig.from_dict(record["config"]).rq1_config()
    config = replace(config, recipe=args.recipe, baselines=(RULE,))
    (scenario,) = config.scenarios
    recorded = record["scenarios"][scenario]
    seeds = [int(s) for s in args.seeds.split(",")] if args.seeds else recorded["rq1"]["seeds"]
    old = {s: f["test"] for s, f in zip(recorded["rq1"]["seeds"],
                                        recorded["rq1"]["methods"][args.method]["figures"],
                                        strict=True)}
    study = Study(DataRoot.resolve(args.root), config, print)
    check_data(study, scenario, recorded)
    load = os.getloadavg()
    t0, c0 = time.perf_counter(), time.process_time()
    if args.method == FUSION_LABEL:
        versions = units.trained_versions(study, scenario, DEFAULT_FAMILY, seeds=seeds,
                                          context_len=FULL_CONTEXT_LEN, modules=list(MODULES))
        monitors = [FAMILIES[DEFAULT_FAMILY].load(study.root, v) for v in versions]
    else:
        monitors = [units.baseline(study, scenario, args.method, s) for s in seeds]
        versions = [m.version for m in monitors]
    wall_s, cpu_s = time.perf_counter() - t0, time.process_time() - c0
    new = {s: units.test_figures(study, scenario, m)["test"]
           for s, m in zip(seeds, monitors, strict=True)}
    cards = {s: read_card(study.root, v) if args.method == FUSION_LABEL else {}
             for s, v in zip(seeds, versions, strict=True)}  # the AEM keeps no training record
    out = {"scenario": scenario, "method": args.method, "recipe": args.recipe, "seeds": seeds,
           "versions": dict(zip(map(str, seeds), versions, strict=True)),
           "load_average": load, "wall_s": wall_s, "cpu_s": cpu_s, "per_seed": {},
           "paired": {}}
    print(f"\n{scenario}, recipe {args.recipe} − recorded, per seed (%):")
    trained = args.method == FUSION_LABEL  # the AEM keeps no training record to show
    print("| seed | " + " | ".join(f"{m} old → new" for m in METRICS)
          + (" | epochs (best) | wall s | CPU s |" if trained else " |"))
    print("|---|" + "---:|" * (len(METRICS) + 3 * trained))
    for s in seeds:
        t = cards[s].get("training") or dict.fromkeys(
            ("epochs_run", "best_epoch", "time_s", "cpu_s"), float("nan"))
        frames = cards[s]["data"]["train"]["frames"] if cards[s] else float("nan")
        out["per_seed"][s] = {"old": {m: old[s][m] for m in METRICS},
                              "new": {m: new[s][m] for m in METRICS},
                              "epochs_run": t["epochs_run"], "best_epoch": t["best_epoch"],
                              "time_s": t["time_s"], "cpu_s": t.get("cpu_s"),
                              "frames_per_cpu_s": frames * t["epochs_run"] / t["cpu_s"]
                              if t.get("cpu_s") else None}
        print(f"| {s} | " + " | ".join(f"{100 * old[s][m]:.1f} → {100 * new[s][m]:.1f}"
                                       for m in METRICS)
              + (f" | {t['epochs_run']} ({t['best_epoch']}) | {t['time_s']:.0f} | "
                 f"{t.get('cpu_s', float('nan')):.0f} |" if trained else " |"))
    print("\n| metric | recorded mean [95 % CI] | new mean | inside | new − recorded [95 % CI] "
          "| p |")
    print("|---|---:|---:|---|---:|---:|")
    for m in METRICS:
        a = [new[s][m] for s in seeds]
        b = [old[s][m] for s in seeds]
        c = compare_paired(a, b)
        ci = mean_ci([old[s][m] for s in old])
        inside = ci.low <= c.mean_a <= ci.high
        out["paired"][m] = {**c.to_dict(), "recorded_ci": ci.to_dict(), "inside": inside}
        print(f"| {m} | {100 * ci.mean:.1f} [{100 * ci.low:.1f}, {100 * ci.high:.1f}] | "
              f"{100 * c.mean_a:.1f} | {'yes' if inside else 'NO'} | "
              f"{100 * c.mean_diff:+.1f} [{100 * c.ci_low:+.1f}, {100 * c.ci_high:+.1f}] | "
              f"{c.p_value:.3g} |")
    print(f"\ntrained in {wall_s:.0f} s wall, {cpu_s:.0f} s CPU (load average {load})")
    if args.out:
        Path(args.out).write_text(json.dumps(out, indent=1, default=float) + "\n",
                                  encoding="utf-8")


if __name__ == "__main__":
    main()
