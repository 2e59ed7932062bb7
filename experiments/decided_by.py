"""How much of a collision the run's own randomness decides, and from when.

    python -m experiments.decided_by --root DIR --regime highway-cut-in:defensive \\
        [--collisions 20] [--draws 5] [--before 5,10,20,30,50,80,120]

Takes the collisions of Uniform's recorded curves of a rare-failure protocol run
(`evoeye results --part rare`, its ledger under DIR) and re-simulates each `draws` times with
both random streams reseeded (`run_episode(branches=…)`):
* `before` frames before its collision: its scenario, initial traffic and every frame up to
  there are the factual run's, only what comes after is drawn again;
* at frame 0: the same θ and initial traffic, every frame's noise drawn again;
* with a fresh run seed: the same θ, its initial traffic drawn again too.
It prints, per offset, the share of re-draws that collide again (Wilson 95 %). A share near 1
means the collision was decided before that point; the gap between frame 0 and a fresh seed is
what the initial traffic decides. docs/rare.md has what it showed, and what it means for
splitting a run in time.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from evoeye.evaluation.stats import proportion_ci
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import parse_regime
from evoeye.results.ledger import Ledger
from evoeye.results.rare.config import REFERENCE, RareConfig
from evoeye.results.rare.runner import run_seed
from evoeye.sim.runner import run_episode, run_spec

FRESH = "fresh seed"


def collisions(root: DataRoot, regime: str) -> list[tuple[dict, int, list[float]]]:
    """(curve inputs, run index, θ) of every collision of Uniform's recorded curves."""
    out = []
    for path in sorted(Ledger(root).folder.glob("rare-curve-*.json")):
        record = json.loads(path.read_bytes())
        key = record["inputs"]
        if key["regime"] != regime or key["strategy"] != REFERENCE:
            continue
        for k, (x, row) in enumerate(zip(record["output"]["x"], record["output"]["runs"],
                                         strict=True)):
            if row["collided"]:
                out.append((key, k, x))
    return sorted(out, key=lambda c: (c[0]["seed"], c[1]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", required=True)
    ap.add_argument("--regime", required=True)
    ap.add_argument("--collisions", type=int, default=20)
    ap.add_argument("--draws", type=int, default=5)
    ap.add_argument("--before", default="5,10,20,30,50,80,120")
    args = ap.parse_args()
    scenario, profile = parse_regime(args.regime)
    offsets = [int(b) for b in args.before.split(",")]
    found = collisions(DataRoot.existing(args.root), args.regime)
    print(f"{args.regime}: {len(found)} collisions in Uniform's curves; re-drawing the first "
          f"{min(len(found), args.collisions)}, {args.draws} times each")
    again: dict[str, list[int]] = {}
    for key, k, x in found[:args.collisions]:
        config = RareConfig(data_seed=key["data_seed"], runs=key["runs"])
        seed = run_seed(config, args.regime, REFERENCE, key["seed"], k)
        spec = run_spec(scenario, np.asarray(x), seed, ads=profile)
        factual = run_episode(spec)
        if not factual.outcome.collided:
            raise SystemExit(f"seed {key['seed']} run {k} did not collide again: not the "
                             "recorded run (another software version?)")
        hit = int(round(factual.outcome.collision_time_s * factual.rate_hz))
        at = {f"{b} before": hit - b for b in offsets if hit - b > 0} | {"frame 0": 0}
        for label, frame in at.items():
            again.setdefault(label, []).append(sum(
                bool(run_episode(spec, branches=((frame, d + 1),)).outcome.collided)
                for d in range(args.draws)))
        fresh = [run_spec(scenario, np.asarray(x), seed + 1 + d, ads=profile)
                 for d in range(args.draws)]
        again.setdefault(FRESH, []).append(sum(bool(run_episode(s).outcome.collided)
                                               for s in fresh))
        print(f"  seed {key['seed']} run {k}: collided at frame {hit}; collide again "
              + ", ".join(f"{label} {v[-1]}/{args.draws}" for label, v in again.items()
                          if label in at or label == FRESH))
    print("re-drawn from | collide again [Wilson 95 %] | collisions re-drawn")
    for label, counts in again.items():
        ci = proportion_ci(sum(counts), args.draws * len(counts))
        print(f"{label} | {sum(counts)}/{args.draws * len(counts)} = {100 * ci.value:.0f} % "
              f"[{100 * ci.low:.0f}, {100 * ci.high:.0f}] | {len(counts)}")


if __name__ == "__main__":
    main()
