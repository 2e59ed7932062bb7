"""What the safety supervisor adds to a run: CPU ms per frame, supervised against plain.

Target: ≤ 0.3 ms per frame. Each of `--runs` concrete scenarios per logical scenario is run
plain (`run_episode`, the ADS alone) and supervised (`run_supervised`: the FusionMonitor through
its RuntimeMonitor beside the ADS, the fallback logic and the per-frame supervisor state), the
two alternated `--repeat` times; the cost is process CPU time (not wall time: the machine is
shared), per frame, median over the runs of each run's best repeat. Two supervised cases:

  watching   a threshold the score never exceeds: the monitor runs, the fallback never acts
  braking    threshold 0: the fallback acts from the first alarm to the end of the run

The monitor is `--monitor VERSION` of `--root`, or an untrained network with normalisers fitted
on the features of the runs (the cost does not depend on the weights).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import torch

from benchmarks.machine import describe
from evoeye.batch import plan_uniform
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import FusionConfig, FusionNet
from evoeye.monitor.online import FrameInputs, FusionScorer
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.registry import load_monitor
from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from evoeye.sim.runner import run_episode
from evoeye.sim.supervisor import Trigger, run_supervised
from evoeye.store.log_windows import episode_run

TARGET_MS = 0.3
CASES = {"watching": 1.0, "braking": 0.0}  # threshold of each supervised case


def untrained(episodes: list) -> FusionMonitor:
    net = FusionNet(FusionConfig())
    windows = [episode_run(ep, "bench.mcap", 5, 3.0).windows for ep in episodes]
    net.fit_normalizers(next(w for w in windows if w is not None).features)
    return FusionMonitor(net.eval(), "untrained", Thresholds({0.05: 0.5}))


def cpu_ms_per_frame(fn) -> float:
    t0 = time.process_time()
    episode = fn()
    return (time.process_time() - t0) * 1e3 / len(episode.frames)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", default=None, help="data root holding --monitor")
    ap.add_argument("--monitor", default=None, help="FusionMonitor version")
    ap.add_argument("--runs", type=int, default=6, help="runs per logical scenario")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    torch.set_num_threads(1)
    specs = {s: plan_uniform(s, args.runs, args.seed) for s in SCENARIOS}
    episodes = [run_episode(sp) for ss in specs.values() for sp in ss[:2]]  # warm-up, too
    monitor = (load_monitor(DataRoot.resolve(args.root), args.monitor) if args.monitor
               else untrained(episodes))
    scorer = FusionScorer(monitor)

    def supervised(spec, threshold: float):
        scorer.reset()
        run = run_supervised(spec, lambda m: scorer.score(FrameInputs.of(m)),
                             Trigger("fusion", monitor.version, (threshold,)))
        return run.episode

    for spec in (ss[0] for ss in specs.values()):  # warm-up: ONNX export, compiled kernels
        supervised(spec, 0.0)
    print(f"machine: {describe()}")
    print(f"monitor: {monitor.version}; {args.runs} runs per scenario, best of {args.repeat}")
    print("| logical scenario | plain ms/frame | "
          + " | ".join(f"{c} ms/frame | {c} added" for c in CASES) + f" | target ≤ {TARGET_MS} |")
    print("|---|---|" + "---|---|" * len(CASES) + "---|")
    for scenario, ss in specs.items():
        plain, added = [], {c: [] for c in CASES}
        for spec in ss:
            best = {k: np.inf for k in ("plain", *CASES)}
            for _ in range(args.repeat):
                best["plain"] = min(best["plain"], cpu_ms_per_frame(lambda s=spec: run_episode(s)))
                for case, threshold in CASES.items():
                    best[case] = min(best[case], cpu_ms_per_frame(
                        lambda s=spec, t=threshold: supervised(s, t)))
            plain.append(best["plain"])
            for case in CASES:
                added[case].append(best[case] - best["plain"])
        med = {c: statistics.median(v) for c, v in added.items()}
        cells = " | ".join(f"{statistics.median(plain) + med[c]:.3f} | **{med[c]:+.3f}**"
                           for c in CASES)
        ok = "yes" if max(med.values()) <= TARGET_MS else "**no**"
        print(f"| {scenario} | {statistics.median(plain):.3f} | {cells} | {ok} |")


if __name__ == "__main__":
    main()
