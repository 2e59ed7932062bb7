"""Simulation throughput: real-time factor of simulate+log vs bare highway-env stepping.

Real-time factor (RTF) = simulated seconds per CPU second of this process, i.e. per core (CPU
time, not wall time, so other load on the machine does not distort it). The bare
reference steps the very same world (same vehicles, same scripts) for the same number of frames
with a fixed ego command, and does nothing else: no ground-truth read, no ADS, no log.
Targets (issue 2): full stack with logging ≥ 50× real time per core, ≤ 2× the bare cost.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.machine import describe
from evoeye.batch import plan_uniform, run_batch
from evoeye.log import write_episode
from evoeye.sim.runner import WORLD_BUILDERS, build_world, run_episode

DT_S = 0.05


def bench_full(specs, out: Path) -> tuple[float, float, float, list[int]]:
    """Sequential simulate + write: (simulated s, wall s, of which writing, frames per run)."""
    sim_s, log_s, frames = 0.0, 0.0, []
    t0 = time.process_time()
    for spec in specs:
        ep = run_episode(spec)
        t_log = time.process_time()
        write_episode(ep, out / f"{spec.scenario_id}.mcap")
        log_s += time.process_time() - t_log
        sim_s += len(ep.frames) * DT_S
        frames.append(len(ep.frames))
    return sim_s, time.process_time() - t0, log_s, frames


def bench_bare(specs, frames: list[int]) -> tuple[float, float]:
    """The same worlds stepped bare for the same number of frames."""
    sim_s, wall_s = 0.0, 0.0
    for spec, n in zip(specs, frames, strict=True):
        world, _ = build_world(spec)
        t0 = time.process_time()
        for _ in range(n):
            world.step(0.0, 0.0, DT_S)
        wall_s += time.process_time() - t0
        sim_s += n * DT_S
    return sim_s, wall_s


def bench_workers(scenario: str, n: int, workers: int) -> float:
    """Wall seconds for a batch of n runs (simulate + log) with `workers` processes (needs an
    otherwise idle machine to mean anything)."""
    specs = plan_uniform(scenario, n, seed=123, batch=f"w{workers}")
    with tempfile.TemporaryDirectory() as root:
        return run_batch(specs, root, workers=workers).wall_s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=20, help="runs per logical scenario")
    args = ap.parse_args()
    print(f"Machine: {describe()}; load average before: {os.getloadavg()[0]:.2f}\n")
    print("| logical scenario | runs | sim s | full RTF (sim+ADS+log) | bare RTF (world) "
          "| full / bare cost | full ms/frame | of which log | 1 worker s | 2 workers s "
          "| speedup |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in WORLD_BUILDERS:
        specs = plan_uniform(name, args.runs, seed=7)
        run_episode(specs[0])  # warm the per-process caches (road networks, imports)
        with tempfile.TemporaryDirectory() as d:
            sim_s, wall_s, log_s, frames = bench_full(specs, Path(d))
        bare_sim, bare_wall = bench_bare(specs, frames)
        full_rtf, bare_rtf = sim_s / wall_s, bare_sim / bare_wall
        w1 = bench_workers(name, args.runs, 1)
        w2 = bench_workers(name, args.runs, 2)
        n_frames = sum(frames)
        print(f"| {name} | {len(specs)} | {sim_s:.0f} | {full_rtf:.1f}× | {bare_rtf:.1f}× "
              f"| {bare_rtf / full_rtf:.2f} | {1e3 * wall_s / n_frames:.3f} "
              f"| {1e3 * log_s / n_frames:.3f} | {w1:.2f} | {w2:.2f} | {w1 / w2:.2f}× |")
    print(f"\nper-frame budget at 20 Hz for 50×: {1000 * DT_S / 50:.2f} ms; "
          f"numpy {np.__version__}")


if __name__ == "__main__":
    main()
