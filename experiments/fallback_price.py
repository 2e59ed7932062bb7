"""What a fallback buys and what it costs, with triggers that know the answer.

    python -m experiments.fallback_price [--n 200] [--cost-n 100] [--seed 4242] \\
        [--workers 2] [--leads 0.5,1,1.5,2,3] [--false-at 4,10] [--out FILE.json]

Simulates `--n` highway-cut-in runs at `--seed` (plan_uniform: the same scenarios and seeds as
`evoeye simulate`), in the default world and with the follower (`evoeye.sim.worlds`), and for
every fallback of FALLBACKS plus staged variants of production:

* **bought**: in each default-world collision run, an oracle alarm from τ s before the known
  collision on (for each τ of `--leads`): the share of those collisions the fallback prevents
  (a collision that only changes partner is not prevented);
* **cost**: in each safe run of the follower world (of the first `--cost-n`), a needless
  brake at each time of `--false-at` — one frame of alarm (the fallback then holds `hold_s`
  and hands back) and a constant one (braking to a stop) — and the share of those that end in
  a collision, and how many of them from behind. The same false brakes in the default world
  cost nothing unless another NPC runs in.

No monitor, no warehouse: a trigger here is a function of the frame time. docs/supervisor.md
and docs/world.md have what it measured.
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

from evoeye.batch import plan_uniform
from evoeye.sim.episode import RunSpec
from evoeye.sim.runner import run_episode
from evoeye.sim.supervisor import FALLBACKS, FallbackConfig, Trigger, run_supervised

TRIGGER = Trigger("oracle", "0", (0.5,))


def fallbacks() -> dict[str, FallbackConfig]:
    """The named fallbacks, and production staged at 4 m/s² for 0.3 and 0.6 s."""
    staged = {f"production+stage4x{s:g}": replace(FALLBACKS["production"], stage_decel_mps2=4.0,
                                                  stage_s=s) for s in (0.3, 0.6)}
    return {**FALLBACKS, **staged}


class Alarm:
    """Risk 1 from `on_s` on (to `off_s`, exclusive; None: to the end), else 0."""

    def __init__(self, on_s: float, off_s: float | None = None) -> None:
        self.on_s, self.off_s = on_s, off_s

    def __call__(self, msgs) -> float:
        t = msgs.localization.t_s
        return float(t >= self.on_s - 1e-9 and (self.off_s is None or t < self.off_s - 1e-9))


def _outcome(spec: RunSpec, alarm: Alarm, config: FallbackConfig) -> tuple[bool, int | None]:
    o = run_supervised(spec, alarm, TRIGGER, config).episode.outcome
    return o.collided, o.other_actor


def bought(spec: RunSpec, leads_s: list[float]) -> dict:
    """Per fallback and τ, whether the oracle engaged τ before the collision prevents it."""
    o = run_episode(spec).outcome
    if not o.collided:
        return {}
    out, moved = {}, {}
    for name, config in fallbacks().items():
        for lead in leads_s:
            collided, partner = _outcome(spec, Alarm(o.collision_time_s - lead), config)
            out[f"{name}|{lead:g}"] = not collided
            moved[f"{name}|{lead:g}"] = collided and partner != o.other_actor
    return {"prevented": out, "other_partner": moved}


def cost(spec: RunSpec, at_s: list[float]) -> dict:
    """Per fallback, false brake time and kind, (collided, struck by the follower)."""
    o = run_episode(spec).outcome
    if o.collided:
        return {}
    follower = None
    out = {}
    for name, config in fallbacks().items():
        for t in at_s:
            for kind, alarm in (("blip", Alarm(t, t + 0.05)), ("constant", Alarm(t))):
                run = run_supervised(spec, alarm, TRIGGER, config)
                follower = len(run.episode.frames[0].scene.x_m) - 1
                r = run.episode.outcome
                struck = r.collided and spec.world == "follower" and r.other_actor == follower
                out[f"{name}|{kind}|{t:g}"] = (r.collided, struck)
    return {"outcomes": out}


def _job(args: tuple[str, RunSpec, list[float]]) -> tuple[str, str, dict]:
    what, spec, values = args
    return what, spec.scenario_id, (bought if what == "bought" else cost)(spec, values)


def _shares(results: list[dict], key: str) -> dict[str, float]:
    keys = sorted({k for r in results for k in r[key]})
    return {k: sum(bool(r[key][k] if key != "outcomes" else r[key][k][0]) for r in results)
            / len(results) for k in keys} if results else {}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--leads", default="0.5,1,1.5,2,3")
    ap.add_argument("--cost-n", type=int, default=100)
    ap.add_argument("--false-at", default="4,10")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    leads = [float(v) for v in a.leads.split(",")]
    at = [float(v) for v in a.false_at.split(",")]
    plain = plan_uniform("highway-cut-in", a.n, a.seed)
    follow = plan_uniform("highway-cut-in", a.n, a.seed, world="follower")
    jobs = ([("bought", s, leads) for s in plain] + [("cost", s, at) for s in follow[:a.cost_n]]
            + [("cost", s, at) for s in plain[:a.cost_n]])
    with ProcessPoolExecutor(a.workers) as pool:
        done = list(pool.map(_job, jobs, chunksize=4))
    by = {"bought": [], "cost-follower": [], "cost-default": []}
    for (what, spec, _), (_, _, r) in zip(jobs, done, strict=True):
        if r:
            by["bought" if what == "bought" else f"cost-{spec.world}"].append(r)
    summary = {
        "n": a.n, "seed": a.seed, "collisions": len(by["bought"]),
        "safe_follower_runs": len(by["cost-follower"]),
        "safe_default_runs": len(by["cost-default"]),
        "prevented": _shares(by["bought"], "prevented"),
        "collided_with_another_partner": _shares(by["bought"], "other_partner"),
        "false_brake_collided_follower": _shares(by["cost-follower"], "outcomes"),
        "false_brake_collided_default": _shares(by["cost-default"], "outcomes"),
        "struck_by_follower": {k: sum(r["outcomes"][k][1] for r in by["cost-follower"])
                               / max(1, len(by["cost-follower"]))
                               for k in sorted({k for r in by["cost-follower"]
                                                for k in r["outcomes"]})},
    }
    text = json.dumps(summary, indent=1)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
