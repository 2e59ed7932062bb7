"""Diagnostics behind the RQ2 write-up (README, "Evolution"): why a strategy wins or loses.

    python -m experiments.rq2_diagnostics feedback-split --root DIR --scenario S --monitor G0
        where G_0's feedback on D_init comes from: misses (unsafe frames scored low) or false
        alarms (safe frames scored high), raw and prior-corrected; all runs and the top decile
    python -m experiments.rq2_diagnostics blind-frames --root DIR --scenario S --monitor G0 \\
            --budget-s B --strategies uniform,avfuzzer,evoeye --seeds 0,1,2
        per campaign: unsafe frames acquired and how many of them G_0 misses at FPR 0.05
    python -m experiments.rq2_diagnostics data-value --root COPY --scenario S --monitor G0 \\
            --budget-s B --strategies uniform,avfuzzer,evoeye --seeds 0,1 --train-seeds 2
        the value of each campaign's final records free of its update path: monitors trained
        from scratch on them (several training seeds), on the Test Set and G_0's Hard Set.
        It adds monitor versions to the root: run it on a copy.
"""

from __future__ import annotations

import argparse

import numpy as np

from evoeye.evolve.campaign.assess import Assessor
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.experiment import brief
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.search.feedback import prior_corrected
from evoeye.monitor.families import load_version
from evoeye.paths import DataRoot
from evoeye.store import RunFilter
from evoeye.store.windows import load_windows


def _campaigns(a: argparse.Namespace):
    for strategy in a.strategies.split(","):
        for seed in (int(s) for s in a.seeds.split(",")):
            cfg = CampaignConfig(a.scenario, strategy=strategy, seed=seed, monitor=a.monitor,
                                 budget_s=a.budget_s, feedback=a.feedback)
            c = Campaign(a.root, cfg)
            yield strategy, seed, c, c.start()


def _acquired_ids(st) -> list[str]:
    return [str(s) for s, ok in zip(st.records.scenario_id[st.n_init:], st.ok[st.n_init:],
                                    strict=True) if ok]


def feedback_split(a: argparse.Namespace) -> None:
    m = load_version(a.root, a.monitor)
    ids = [str(s) for s in Campaign(a.root, CampaignConfig(a.scenario, monitor=a.monitor))
           .initial["scenario_id"]]
    w = load_windows(a.root, ids, context_len=m.context_len, horizon_s=3.0)
    raw, y = m.score(w), w.label.astype(float)
    for name, s in (("raw", raw), ("prior-corrected",
                                   prior_corrected(raw, m.card["hyperparameters"]["pos_weight"]))):
        err = np.abs(s - y)
        runs = (w.scenario_id == r for r in np.unique(w.scenario_id))
        rows = np.array([(err[k & (y == 1)].sum() / k.sum(), err[k & (y == 0)].sum() / k.sum(),
                          y[k].any()) for k in runs])
        f = rows[:, 0] + rows[:, 1]
        for part, sel in (("all", np.argsort(-f)), ("top 10%", np.argsort(-f)[: len(f) // 10])):
            b = rows[sel]
            total = b[:, :2].sum()
            print(f"{name:16s} {part:8s} runs {len(b):4d}  misses {b[:, 0].sum() / total:.0%}  "
                  f"false alarms {b[:, 1].sum() / total:.0%}  collision runs {b[:, 2].mean():.0%}")


def blind_frames(a: argparse.Namespace) -> None:
    m = load_version(a.root, a.monitor)
    threshold = m.thresholds.at(0.05)
    for strategy, seed, _, st in _campaigns(a):
        w = load_windows(a.root, _acquired_ids(st), context_len=m.context_len, horizon_s=3.0)
        unsafe = w.label == 1
        missed = unsafe & (m.score(w) <= threshold)
        print(f"{strategy} s{seed}: runs {len(_acquired_ids(st))}, unsafe frames {unsafe.sum()}, "
              f"missed by G_0 {missed.sum()} in {len(set(w.scenario_id[missed]))} runs")


def data_value(a: argparse.Namespace) -> None:
    from evoeye.monitor import train_monitor

    assess = Assessor(a.root, a.scenario, a.monitor)
    val = RunFilter(logical_scenario=a.scenario, split="val")
    for strategy, seed, _, st in _campaigns(a):
        ids = [str(s) for s, ok in zip(st.records.scenario_id, st.ok, strict=True) if ok]
        for k in range(a.train_seeds):
            m = assess(train_monitor(a.root, a.scenario, train_runs=ids, val_runs=val,
                                     seed=100 + k))
            print(f"{strategy} s{seed} train-seed {k}: {brief(m)}",
                  flush=True)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", choices=("feedback-split", "blind-frames", "data-value"))
    ap.add_argument("--root", type=DataRoot.resolve, required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--monitor", required=True, help="G_0")
    ap.add_argument("--budget-s", type=float, default=0.0)
    ap.add_argument("--strategies", default="uniform,avfuzzer,evoeye")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--feedback", default="raw")
    ap.add_argument("--train-seeds", type=int, default=2)
    a = ap.parse_args(argv)
    {"feedback-split": feedback_split, "blind-frames": blind_frames,
     "data-value": data_value}[a.command](a)


if __name__ == "__main__":
    main()
