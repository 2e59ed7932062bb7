"""What the safety supervisor adds to a run: CPU ms per frame, supervised against plain.

Target: ≤ 0.3 ms per frame. Each of `--runs` concrete scenarios per logical scenario is run
plain (`run_episode`, the ADS alone) and supervised (`run_supervised`: the FusionMonitor through
its RuntimeMonitor beside the ADS, the fallback logic and the per-frame supervisor state), the
two alternated `--repeat` times; the cost is process CPU time (not wall time: the machine is
shared), per frame, median over the runs of each run's best repeat. Two supervised cases:

  watching   a threshold the score never exceeds: the monitor runs, the fallback never acts
  braking    threshold 0: the fallback acts from the first alarm to the end of the run

The monitor is `--monitor VERSION` of `--root`, or an untrained network with normalisers fitted
on the features of the runs (the cost does not depend on the weights). `--parts` adds where the
watching cost goes: CPU time around the features (`FrameInputs.of`) and the scorer (context
buffers and ONNX Runtime) inside the loop, against the same frames in a tight loop.
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


def parts(scorer: FusionScorer, specs: list, version: str) -> None:
    """Per frame: features and scorer timed inside the loop, then in a tight loop."""
    spent = {"features": 0.0, "scorer": 0.0}
    frames: list = []

    def timed(messages) -> float:
        t0 = time.process_time()
        inputs = FrameInputs.of(messages)
        t1 = time.process_time()
        score = scorer.score(inputs)
        spent["features"] += t1 - t0
        spent["scorer"] += time.process_time() - t1
        frames.append(messages)
        return score

    for spec in specs:
        scorer.reset()
        run_supervised(spec, timed, Trigger("fusion", version, (1.0,)))
    n = len(frames)
    t0 = time.process_time()
    inputs = [FrameInputs.of(m) for m in frames]
    t1 = time.process_time()
    scorer.reset()
    for f in inputs:
        scorer.score(f)
    t2 = time.process_time()
    print(f"parts ({n} frames, ms/frame): in the loop features {1e3 * spent['features'] / n:.3f}"
          f", scorer {1e3 * spent['scorer'] / n:.3f}; tight loop features "
          f"{1e3 * (t1 - t0) / n:.3f}, scorer {1e3 * (t2 - t1) / n:.3f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", default=None, help="data root holding --monitor")
    ap.add_argument("--monitor", default=None, help="FusionMonitor version")
    ap.add_argument("--runs", type=int, default=6, help="runs per logical scenario")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--parts", action="store_true", help="also time features and scorer")
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
    if args.parts:
        for scenario, ss in specs.items():
            print(scenario, end=": ")
            parts(scorer, ss, monitor.version)


if __name__ == "__main__":
    main()
