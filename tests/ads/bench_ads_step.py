"""Per-frame cost of `ADS.step` with 6 obstacles in closed loop (a script, not a test).

    .venv/bin/python tests/ads/bench_ads_step.py

The loop is deterministic, so it is run REPS times and every frame keeps its fastest run, which
filters out noise from other processes; the plain median over the runs is printed too.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[2]))  # this checkout's evoeye, not an installed one
from conftest import BicycleWorld, crossing_road, straight_road  # noqa: E402

from evoeye.ads import ADS, ADSConfig  # noqa: E402

FRAMES, REPS, WARMUP = 300, 7, 20
HIGHWAY = [(45, 0, 0, 20), (25, 4, 0, 20), (12, -4, 0, 20), (-18, 4, 0, 20), (60, -4, 0, 20),
           (-20, 0, 0, 20)]
CROSSING = [(-25, 0, 0, 2), (25, 0, math.pi, 2), (-4, 40, -math.pi / 2, 1),
            (-4, 20, -math.pi / 2, 1), (-15, -4, 0, 1), (0, 25, math.pi / 2, 3)]


def run(road, ego, npcs, cruise):
    world = BicycleWorld(ego=list(ego), npcs=[list(n) for n in npcs])
    ads = ADS(road, np.random.default_rng(1), ADSConfig.cautious().with_cruise_speed(cruise))
    times, n_obs = [], []
    for _ in range(FRAMES):
        scene = world.scene()
        t0 = time.perf_counter()
        msgs = ads.step(scene)
        times.append(time.perf_counter() - t0)
        n_obs.append(len(msgs.obstacles.track_id))
        world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad)
    return np.array(times[WARMUP:]), np.array(n_obs[WARMUP:])


def bench(name, road, ego, npcs, cruise):
    runs = [run(road, ego, npcs, cruise) for _ in range(REPS)]
    best = np.min([t for t, _ in runs], axis=0) * 1e3
    plain = np.median([np.median(t) for t, _ in runs]) * 1e3
    n_obs = runs[0][1]
    print(f"{name:9s} median {np.median(best):.3f} ms (best of {REPS} per frame), "
          f"p90 {np.percentile(best, 90):.3f} ms, plain median {plain:.3f} ms, "
          f"obstacles {n_obs.mean():.1f} (min {n_obs.min()})")


if __name__ == "__main__":
    bench("highway", straight_road(), (0, 0, 0, 20), HIGHWAY, 20.0)
    bench("crossing", crossing_road(), (0, -20, math.pi / 2, 3), CROSSING, 3.0)
