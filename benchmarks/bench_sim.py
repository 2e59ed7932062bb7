"""Simulation throughput: real-time factor of simulate+log vs bare highway-env stepping.

Real-time factor (RTF) = simulated seconds per CPU second of this process, i.e. per core (CPU
time, not wall time, so other load on the machine does not distort it). The bare reference is
highway-env simulating the same vehicles its own way (`road.act(); road.step(dt)` with its IDM
vehicles at the same poses, speeds and desired speeds, a fixed ego command) for the same number
of frames, and nothing else: no ground-truth read, no ADS, no log. Our world steps its NPCs
itself (bounded path dynamics, vectorised relations and contacts), more cheaply than
highway-env does, so the table also gives the cost relative to our own bare world.
`--engines`: the per-run engine against the lockstep one (`evoeye.sim.lockstep`), simulate +
log, on the same runs, CPU s per run (issue 41: ≥ 3×, logs included). `--stages`: where a
lockstep run's CPU goes, stage by stage, and what the ratio would be if a stage cost nothing.
Targets (issues 2 and 10): full stack with logging ≥ 50× real time per core, ≤ 2× the cost of
bare highway-env stepping of the same vehicles.
"""

from __future__ import annotations

import argparse
import io
import math
import os
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from highway_env.road.road import Road
from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.kinematics import Vehicle

from benchmarks.machine import describe
from evoeye.batch import plan_uniform, run_batch
from evoeye.log import write_episode
from evoeye.log.writer import write_stream
from evoeye.paths import DataRoot
from evoeye.phases import PhaseClock
from evoeye.scenarios import SCENARIOS
from evoeye.sim import lockstep
from evoeye.sim.lockstep import run_lockstep
from evoeye.sim.runner import RunLoop, build_world, run_episode

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


def highway_env_road(world) -> Road:
    """The same vehicles as highway-env's own: a kinematic ego and an IDM vehicle for every NPC
    (same road, pose, speed, desired speed), as highway-env would simulate them. NPCs check no
    collisions (only the ego does), which keeps the reference as cheap as it can be."""
    road = Road(network=world.road.network, np_random=np.random.default_rng(0),
                record_history=False)
    ego = Vehicle(road, world.ego.position.copy(), world.ego.heading, world.ego.speed)
    ego.action = {"acceleration": 0.0, "steering": 0.0}
    road.vehicles.append(ego)
    for npc in world.npcs:
        v = IDMVehicle(road, npc.position.copy(), npc.heading, npc.speed,
                       target_lane_index=npc.lane_index, target_speed=npc.desired_speed_mps,
                       enable_lane_change=False)
        v.check_collisions = False
        road.vehicles.append(v)
    return road


def bench_bare(specs, frames: list[int]) -> tuple[float, float, float]:
    """The same vehicles stepped bare for the same number of frames: (simulated s, CPU s with
    highway-env's own stepping, CPU s with our world's stepping)."""
    sim_s, henv_s, world_s = 0.0, 0.0, 0.0
    for spec, n in zip(specs, frames, strict=True):
        world, _ = build_world(spec)
        road = highway_env_road(world)
        t0 = time.process_time()
        for _ in range(n):
            road.act()
            road.step(DT_S)
        henv_s += time.process_time() - t0
        t0 = time.process_time()
        for _ in range(n):
            world.step(0.0, 0.0, DT_S)
        world_s += time.process_time() - t0
        sim_s += n * DT_S
    return sim_s, henv_s, world_s


def bench_workers(scenario: str, n: int, workers: int) -> float:
    """Wall seconds for a batch of n runs (simulate + log) with `workers` processes (needs an
    otherwise idle machine to mean anything)."""
    specs = plan_uniform(scenario, n, seed=123, batch=f"w{workers}")
    with tempfile.TemporaryDirectory() as root:
        return run_batch(specs, DataRoot.resolve(root), workers=workers).wall_s


def bench_engines(specs, sizes: list[int], repeat: int) -> dict:
    """CPU s per run on the same specs, simulation and log apart: the per-run engine and the
    lockstep engine at each batch size, interleaved `repeat` times, best of each; and how many
    lockstep runs have the per-run run's log bytes and outcome (equivalence)."""
    best = {"per-run": (math.inf, math.inf), **dict.fromkeys(sizes, (math.inf, math.inf))}
    same_bytes, same_outcome = dict.fromkeys(sizes, 0), dict.fromkeys(sizes, 0)
    for _ in range(repeat):
        t0 = time.process_time()
        ref = {s.scenario_id: run_episode(s) for s in specs}
        sim = time.process_time() - t0
        ref_bytes, log = _logs(ref.values())
        best["per-run"] = min(best["per-run"], (sim / len(specs), log / len(specs)))
        ref = {k: e.outcome for k, e in ref.items()}  # the episodes go: both engines write with
        # only their own episodes alive (more live objects make Python's collector slower)
        for size in sizes:
            t0 = time.process_time()
            got = {e.spec.scenario_id: e for e in run_lockstep(specs, size=size)}
            sim = time.process_time() - t0
            got_bytes, log = _logs(got.values())
            best[size] = min(best[size], (sim / len(specs), log / len(specs)))
            same_bytes[size] = sum(got_bytes[k] == ref_bytes[k] for k in ref)
            same_outcome[size] = sum(got[k].outcome == ref[k] for k in ref)
            del got
    return {"best": best, "same_bytes": same_bytes, "same_outcome": same_outcome,
            "collided": sum(o.collided for o in ref.values())}


def _logs(episodes) -> tuple[dict[str, bytes], float]:
    """Each episode's log bytes, and the CPU s it took to write them."""
    t0 = time.process_time()
    out = {}
    for episode in episodes:
        f = io.BytesIO()
        write_stream(episode, f)
        out[episode.spec.scenario_id] = f.getvalue()
    return out, time.process_time() - t0


def engines_table(runs: int, sizes: list[int], repeat: int, seed: int, profiles: list[str]) -> None:
    print("CPU ms per run: simulation + log (× the per-run engine, with the log; simulation "
          "alone)")
    print("| logical scenario | ADS | runs (collided) | per-run engine | "
          + " | ".join(f"lockstep B={b}" for b in sizes)
          + " | same log bytes, same outcome |")
    print("|---|---|---|---|" + "---|" * len(sizes) + "---|")
    for name in SCENARIOS:
        for ads in profiles:
            specs = plan_uniform(name, runs, seed=seed, ads=ads)
            run_episode(specs[0])  # warm the per-process caches (road networks, imports)
            r = bench_engines(specs, sizes, repeat)
            ref_sim, ref_log = r["best"]["per-run"]
            cells = []
            for b in sizes:
                sim, log = r["best"][b]
                cells.append(f"{1e3 * sim:.0f} + {1e3 * log:.0f} "
                             f"(×{(ref_sim + ref_log) / (sim + log):.2f}; ×{ref_sim / sim:.2f})")
            same = ", ".join(f"{r['same_bytes'][b]}/{runs}, {r['same_outcome'][b]}/{runs}"
                             for b in sizes)
            print(f"| {name} | {ads} | {runs} ({r['collided']}) | {1e3 * ref_sim:.0f} + "
                  f"{1e3 * ref_log:.0f} | {' | '.join(cells)} | {same} |")


# a lockstep frame's stages: the names `_lockstep` calls them by (owner, attribute)
STAGES = {"world read": (lockstep, "scenes"), "ADS": (lockstep, "step_batch"),
          "record and finiteness checks": (RunLoop, "record"),
          "world step": (lockstep, "step_worlds")}


@contextmanager
def timed_stages(clock: PhaseClock) -> Iterator[None]:
    """Each of STAGES counted on `clock` while the block runs (the functions themselves are
    called unchanged); restored after."""
    saved = {name: getattr(owner, attr) for name, (owner, attr) in STAGES.items()}

    def timed(name, fn):
        def call(*args, **kwargs):
            with clock(name):
                return fn(*args, **kwargs)
        return call

    try:
        for name, (owner, attr) in STAGES.items():
            setattr(owner, attr, timed(name, saved[name]))
        yield
    finally:
        for name, (owner, attr) in STAGES.items():
            setattr(owner, attr, saved[name])


def stages_table(runs: int, size: int, seed: int, profiles: list[str], repeat: int) -> None:
    """CPU ms per run of each stage of the lockstep engine (the rest of its loop: "other"), the
    log, and × the per-run engine with the log if that stage alone cost nothing; the engines
    interleaved `repeat` times, the best per-run pass against the best lockstep pass."""
    phases = [*STAGES, "other", "log"]
    print(f"CPU ms per run of a lockstep run (B = {size}) by stage; in brackets × the per-run "
          "engine, with the log, if that stage cost nothing")
    print("| logical scenario | ADS | per-run engine, with the log | lockstep, with the log | "
          + " | ".join(phases) + " |")
    print("|---|---|---:|---:|" + "---:|" * len(phases))
    for name in SCENARIOS:
        for ads in profiles:
            specs = plan_uniform(name, runs, seed=seed, ads=ads)
            run_episode(specs[0])  # warm the per-process caches
            per_run, ms = math.inf, {}
            for _ in range(repeat):
                t0 = time.process_time()
                ref = [run_episode(s) for s in specs]
                per_run = min(per_run, 1e3 * (time.process_time() - t0 + _logs(ref)[1]) / runs)
                del ref  # each engine runs with only its own episodes alive
                clock = PhaseClock(phases)
                with clock("other"), timed_stages(clock):
                    got = list(run_lockstep(specs, size=size))
                with clock("log"):
                    _logs(got)
                del got
                this = {p: 1e3 * clock.cpu_seconds[p] / runs for p in phases}
                if not ms or sum(this.values()) < sum(ms.values()):
                    ms = this
            total = sum(ms.values())
            cells = [f"{ms[p]:.0f} (×{per_run / (total - ms[p]):.2f})" for p in phases]
            print(f"| {name} | {ads} | {per_run:.0f} | {total:.0f} (×{per_run / total:.2f}) | "
                  + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=20, help="runs per logical scenario")
    ap.add_argument("--engines", action="store_true",
                    help="only the per-run against the lockstep engine, side by side")
    ap.add_argument("--sizes", type=int, nargs="+", default=[8, 64],
                    help="lockstep batch sizes for --engines")
    ap.add_argument("--repeat", type=int, default=2,
                    help="interleaved repeats for --engines and --stages")
    ap.add_argument("--seed", type=int, default=7,
                    help="batch seed of the runs (--engines, --stages)")
    ap.add_argument("--ads", nargs="+", default=["default"],
                    help="ADS profiles (--engines, --stages)")
    ap.add_argument("--stages", action="store_true",
                    help="only the lockstep engine's CPU by stage (at the first of --sizes)")
    args = ap.parse_args()
    print(f"Machine: {describe()}; load average before: {os.getloadavg()[0]:.2f}\n")
    if args.stages:
        stages_table(args.runs, args.sizes[0], args.seed, args.ads, args.repeat)
        return
    if args.engines:
        engines_table(args.runs, args.sizes, args.repeat, args.seed, args.ads)
        return
    print("| logical scenario | runs | sim s | full RTF (sim+ADS+log) "
          "| bare RTF (highway-env) | full / bare cost | bare RTF (our world) "
          "| full / world cost | full ms/frame | of which log | 1 worker s | 2 workers s "
          "| speedup |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in SCENARIOS:
        specs = plan_uniform(name, args.runs, seed=7)
        run_episode(specs[0])  # warm the per-process caches (road networks, imports)
        with tempfile.TemporaryDirectory() as d:
            sim_s, wall_s, log_s, frames = bench_full(specs, Path(d))
        bare_sim, henv_wall, world_wall = bench_bare(specs, frames)
        full_rtf, bare_rtf, world_rtf = sim_s / wall_s, bare_sim / henv_wall, bare_sim / world_wall
        w1 = bench_workers(name, args.runs, 1)
        w2 = bench_workers(name, args.runs, 2)
        n_frames = sum(frames)
        print(f"| {name} | {len(specs)} | {sim_s:.0f} | {full_rtf:.1f}× | {bare_rtf:.1f}× "
              f"| {bare_rtf / full_rtf:.2f} | {world_rtf:.1f}× | {world_rtf / full_rtf:.2f} "
              f"| {1e3 * wall_s / n_frames:.3f} "
              f"| {1e3 * log_s / n_frames:.3f} | {w1:.2f} | {w2:.2f} | {w1 / w2:.2f}× |")
    print(f"\nper-frame budget at 20 Hz for 50×: {1000 * DT_S / 50:.2f} ms; "
          f"numpy {np.__version__}")


if __name__ == "__main__":
    main()
