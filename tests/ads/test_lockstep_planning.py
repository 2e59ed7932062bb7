"""Batched planning (`evoeye.ads.lockstep.planning`) against each run's own planner.

The predictions and egos are those of real runs, built and stepped as `run_episode` does, for
every scenario and two ADS profiles, on seeds whose runs cruise, follow, yield, proceed, brake
hard and collide. Fresh planners replay them through `plan_batch`: per regime, one run at a
time, every regime mixed in one shuffled batch, and in copies enough for `np.interp` to take
its other branch. After every frame, every plan (each field, bit for bit) and every planner's
state must be what the run's own planner made of the same frame. Dense synthetic obstacles about
each route (track ids −1 and 0 among them, egos faster than their cruise speed) reach the
corners real runs rarely do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from evoeye.ads import ADS, ads_profile
from evoeye.ads.lockstep import planning as lockstep_planning
from evoeye.ads.lockstep.planning import plan_batch
from evoeye.ads.messages import PLANNING_DECISIONS, Localization, PlannedTrajectory, Predictions
from evoeye.ads.planning import RoutePlanner
from evoeye.batch import plan_uniform
from evoeye.scenarios import SCENARIOS
from evoeye.sim.runner import SimConfig, _seeds, build_world

PROFILES = ("default", "cautious")
SEEDS = {"highway-cut-in": 0, "unprotected-intersection": 4, "occluded-crossing": 0}
RUNS = 4  # runs per regime
FRAMES = 80
STATE = ("_plan_v", "_plan_a", "_hold_id", "_hold_decision", "_clear_frames", "_stop_s",
         "_proceeding")


def bits(value) -> tuple:
    """A value as its exact bits: an array's dtype, shape and bytes, a float's hex (−0.0 is
    not 0.0), anything else itself, with its type."""
    if isinstance(value, np.ndarray):
        return (np.ndarray, value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, float):
        return (type(value), value.hex())
    return (type(value), value)


def plan_bits(plan: PlannedTrajectory) -> tuple:
    return tuple(bits(v) for v in plan.field_values())


def state_bits(planner: RoutePlanner) -> tuple:
    return tuple(bits(getattr(planner, name)) for name in STATE)


@dataclass
class Run:
    args: tuple  # the RoutePlanner arguments of the run's ADS
    frames: list[tuple]  # per frame: predictions, ego, the plan's bits, the planner's state bits
    collided: bool


def step_run(spec) -> Run:
    """The run as `run_episode` steps it (exact frame times; it ends `post_collision_s` after a
    collision), keeping what its planner was given, planned and was left with at every frame."""
    world_rng, ads_rng = _seeds(spec.seed)
    world, cruise = build_world(spec, world_rng)
    ads = ADS(world.road_map, ads_rng, ads_profile(spec.ads).with_cruise_speed(cruise))
    sim = SimConfig()
    dt = 1.0 / sim.rate_hz
    post = int(round(sim.post_collision_s * sim.rate_hz))
    frames, hit = [], None
    for k in range(FRAMES):
        scene = world.scene()
        scene.t_s = k * dt
        msgs = ads.step(scene)
        frames.append((msgs.predictions, msgs.localization, plan_bits(msgs.plan),
                       state_bits(ads.planner)))
        if scene.ego_collision and hit is None:
            hit = k
        if hit is not None and k >= hit + post:
            break
        world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad, dt)
    c = ads.config
    return Run((world.road_map, c.planning, c.cruise_speed_mps, c.frame_dt_s), frames,
               hit is not None)


@pytest.fixture(scope="module")
def regimes() -> dict[tuple[str, str], list[Run]]:
    return {(s, p): [step_run(spec) for spec in plan_uniform(s, RUNS, seed=SEEDS[s], ads=p)]
            for s in SCENARIOS for p in PROFILES}


@pytest.fixture
def spy(monkeypatch) -> dict[str, list]:
    """What the batch did: the size of every group planned together, and for every batched
    crossing computation whether some row had a proceed margin and some a held track."""
    seen: dict[str, list] = {"groups": [], "crossings": []}
    prepare, crossings = lockstep_planning._prepare, RoutePlanner._crossings

    def group_spy(planners, predictions, egos):
        seen["groups"].append(len(planners))
        return prepare(planners, predictions, egos)

    def crossings_spy(self, w, i, ids, dt, s_e, v, vc, margin, held):
        if isinstance(v, np.ndarray):  # batched rows, not a run alone
            seen["crossings"].append((len(np.unique(s_e)), isinstance(margin, np.ndarray)
                                      and bool((margin != self.c.gap_margin_s).any()),
                                      held is not None and bool(held.any())))
        return crossings(self, w, i, ids, dt, s_e, v, vc, margin, held)

    monkeypatch.setattr(lockstep_planning, "_prepare", group_spy)
    monkeypatch.setattr(RoutePlanner, "_crossings", crossings_spy)
    return seen


def replay(runs: list[Run], batch: int, shuffle: np.random.Generator | None = None) -> int:
    """Replay the runs' frames through fresh planners, `batch` runs still going per
    `plan_batch` call, checking every plan and state; the number of run-frames checked."""
    planners = [RoutePlanner(*r.args) for r in runs]
    checked = 0
    for k in range(max(len(r.frames) for r in runs)):
        live = [j for j, r in enumerate(runs) if k < len(r.frames)]
        if shuffle is not None:
            live = [live[i] for i in shuffle.permutation(len(live))]
        for at in range(0, len(live), batch):
            js = live[at:at + batch]
            plans = plan_batch([planners[j] for j in js], [runs[j].frames[k][0] for j in js],
                               [runs[j].frames[k][1] for j in js])
            assert len(plans) == len(js)
            for j, plan in zip(js, plans, strict=True):
                _, _, want_plan, want_state = runs[j].frames[k]
                assert plan_bits(plan) == want_plan, (j, k)
                assert state_bits(planners[j]) == want_state, (j, k)
                checked += 1
    return checked


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("profile", PROFILES)
def test_every_frame_of_real_runs_batched_and_alone(regimes, spy, scenario, profile):
    runs = regimes[scenario, profile]
    total = sum(len(r.frames) for r in runs)
    assert total >= RUNS * 50
    assert replay(runs, RUNS) == total
    assert spy["groups"] and max(spy["groups"]) == RUNS  # the batch was batched
    spy["groups"].clear()
    assert replay(runs, 1) == total  # B = 1
    assert not spy["groups"]


def test_every_regime_mixed_in_one_shuffled_batch(regimes, spy):
    runs = [r for rs in regimes.values() for r in rs]
    assert replay(runs, len(runs), np.random.default_rng(5)) == sum(len(r.frames) for r in runs)
    # a group per route and config: one per regime whose runs are still going (all, at first)
    assert spy["groups"][: len(regimes)] == [RUNS] * len(regimes)
    assert len(spy["groups"]) >= FRAMES * len(regimes) * 0.9
    rows = spy["crossings"]
    assert any(runs > 1 for runs, _, _ in rows)  # crossings of several runs computed at once
    assert any(margin for _, margin, _ in rows)  # of runs proceeding past a track …
    assert any(held for _, _, held in rows)  # … and of runs yielding to one


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_a_batch_large_enough_for_interp_to_precompute_its_slopes(regimes, scenario):
    """np.interp computes the slopes of its table up front once it has more points to
    interpolate than table entries, else per point: both must give the same bits."""
    runs = regimes[scenario, "default"]
    route = RoutePlanner(*runs[0].args).route
    copies = math.ceil(len(route._ig) / (41 * RUNS))  # 41 points per plan
    assert RUNS * copies * 41 >= len(route._ig) > 41
    assert replay(runs * copies, RUNS * copies) == copies * sum(len(r.frames) for r in runs)


def test_the_runs_reach_every_decision_collide_and_see_nothing(regimes):
    decisions, empty, collided = set(), 0, 0
    for runs in regimes.values():
        for r in runs:
            collided += r.collided
            for predictions, _, plan, _ in r.frames:
                decisions.add(plan[1][1])
                empty += len(predictions.track_id) == 0
    assert decisions == set(PLANNING_DECISIONS)
    assert empty > 0 and collided > 0


def test_egos_off_the_route_take_the_full_search_and_a_nan_ego_raises(regimes):
    runs = regimes["occluded-crossing", "default"]
    k = 30
    preds = [r.frames[k][0] for r in runs]
    egos = [r.frames[k][1] for r in runs]
    egos = [replace(egos[0], x_m=egos[0].x_m + 3.0e3), replace(egos[1], y_m=-1.0e7), *egos[2:]]
    alone = [RoutePlanner(*r.args).plan(p, e) for r, p, e in zip(runs, preds, egos, strict=True)]
    batched = plan_batch([RoutePlanner(*r.args) for r in runs], preds, egos)
    assert [plan_bits(p) for p in batched] == [plan_bits(p) for p in alone]
    egos[2] = replace(egos[2], x_m=math.nan)
    with pytest.raises(ValueError):
        RoutePlanner(*runs[2].args).plan(preds[2], egos[2])
    with pytest.raises(ValueError):
        plan_batch([RoutePlanner(*r.args) for r in runs], preds, egos)


def test_a_batch_that_raises_leaves_every_planner_as_it_was(regimes, monkeypatch):
    """The batch's runs are planned again one by one after it raises (`lockstep.stack`): no
    planner may have moved on, whether its own group or another raised, in the array work
    (a NaN ego) or in a decision."""
    runs = regimes["occluded-crossing", "default"] + regimes["occluded-crossing", "cautious"]
    planners = [RoutePlanner(*r.args) for r in runs]
    for k in range(45):  # into the yields and proceeds, with state to lose
        plan_batch(planners, [r.frames[k][0] for r in runs], [r.frames[k][1] for r in runs])
    k = 45
    preds = [r.frames[k][0] for r in runs]
    before = [state_bits(p) for p in planners]
    bad = [replace(r.frames[k][1], y_m=math.nan) if j == len(runs) - 1 else r.frames[k][1]
           for j, r in enumerate(runs)]
    with pytest.raises(ValueError):
        plan_batch(planners, preds, bad)
    assert [state_bits(p) for p in planners] == before
    decide = RoutePlanner._decide

    def fail_last(self, *args):  # once its state has changed
        decided = decide(self, *args)
        if self is planners[RUNS - 1]:
            raise RuntimeError("a decision fails")
        return decided

    monkeypatch.setattr(RoutePlanner, "_decide", fail_last)
    with pytest.raises(RuntimeError):
        plan_batch(planners, preds, [r.frames[k][1] for r in runs])
    assert [state_bits(p) for p in planners] == before
    j = RUNS - 1
    with pytest.raises(RuntimeError):  # B = 1
        plan_batch([planners[j]], [preds[j]], [runs[j].frames[k][1]])
    assert state_bits(planners[j]) == before[j]
    monkeypatch.setattr(RoutePlanner, "_decide", decide)
    plans = plan_batch(planners, preds, [r.frames[k][1] for r in runs])
    assert [plan_bits(p) for p in plans] == [r.frames[k][2] for r in runs]


def test_other_planners_plan_alone_and_a_planner_is_in_a_batch_once(regimes):
    class Cautious(RoutePlanner):
        def plan(self, predictions: Predictions, ego):
            plan = super().plan(predictions, ego)
            plan.target_speed_mps = min(plan.target_speed_mps, 1.0)
            return plan

    runs = regimes["highway-cut-in", "cautious"]
    k = 40
    preds = [r.frames[k][0] for r in runs]
    egos = [r.frames[k][1] for r in runs]
    planners = [Cautious(*runs[0].args), *[RoutePlanner(*r.args) for r in runs[1:]]]
    batched = plan_batch(planners, preds, egos)
    assert batched[0].target_speed_mps <= 1.0
    alone = [Cautious(*runs[0].args), *[RoutePlanner(*r.args) for r in runs[1:]]]
    assert [plan_bits(p) for p in batched] == [
        plan_bits(p.plan(pr, e)) for p, pr, e in zip(alone, preds, egos, strict=True)]
    with pytest.raises(ValueError, match="one planner for several"):
        plan_batch([planners[1], planners[1]], preds[:2], egos[:2])
    with pytest.raises(ValueError, match="one planner, predictions and ego per run"):
        plan_batch(planners, preds[:2], egos)


def synthetic_frames(route, rng: np.random.Generator, frames: int) -> list[tuple]:
    """An ego driving along the route (at times faster than its cruise speed, a little off the
    centre line) among constant-velocity obstacles about it, re-drawn now and then: aligned,
    crossing, oncoming or anyhow, some standing, some with a second mode as likely as not; track
    ids from a small set that includes −1 and 0."""
    t = (np.arange(30) + 1.0) * 0.1
    g, speed = float(route.length_m[0]) * rng.uniform(0.1, 0.5), rng.uniform(0.0, 25.0)
    out, obstacles = [], None
    for f in range(frames):
        if obstacles is None or rng.random() < 0.04:
            n = int(rng.integers(0, 8))
            og = g + rng.uniform(-15.0, 70.0, n)
            rx, ry = route.xy_at(og)
            rh = route.heading_at(og)
            lat = rng.normal(0.0, 4.0, n)
            rel = rng.choice([0.0, math.pi / 2, -math.pi / 2, math.pi, 1.0], n)
            heading = rh + rel + rng.normal(0.0, 0.1, n)
            v = rng.uniform(0.0, 15.0, n) * (rng.random(n) > 0.15)
            obstacles = [rx - lat * np.sin(rh), ry + lat * np.cos(rh), v * np.cos(heading),
                         v * np.sin(heading), rng.choice([-1, 0, 1, 2, 3, 5, 8, 13], n, False),
                         rng.uniform(4.0, 5.0, n), rng.uniform(1.8, 2.1, n)]
        else:
            obstacles[0] = obstacles[0] + obstacles[2] * 0.05
            obstacles[1] = obstacles[1] + obstacles[3] * 0.05
        x, y, vx, vy, ids, length, width = obstacles
        second = rng.random(len(x)) < 0.3  # a second mode, turned and slower or faster
        turn, scale = rng.normal(0.0, 0.4, len(x)), rng.uniform(0.5, 1.5, len(x))
        c, s = np.cos(turn) * scale, np.sin(turn) * scale
        rows = np.repeat(np.arange(len(x)), 1 + second)
        alt = np.zeros(len(rows), dtype=bool)
        alt[1:] = rows[1:] == rows[:-1]
        rvx = np.where(alt, (c * vx - s * vy)[rows], vx[rows])
        rvy = np.where(alt, (s * vx + c * vy)[rows], vy[rows])
        prob = np.where(alt, rng.uniform(0.0, 0.7, len(rows)), rng.uniform(0.3, 1.0, len(rows)))
        predictions = Predictions(
            t_s=f * 0.05, dt_s=0.1, track_id=ids[rows].astype(np.int64),
            model=["cv"] * len(rows), mode_prob=prob, length_m=length[rows],
            width_m=width[rows], x_m=x[rows, None] + rvx[:, None] * t,
            y_m=y[rows, None] + rvy[:, None] * t,
        )
        ex, ey = route.xy_at(np.array([g]))
        eh = route.heading_at(np.array([g]))
        off = rng.normal(0.0, 0.3)
        ego = Localization(t_s=f * 0.05, x_m=float(ex[0] - off * math.sin(eh[0])),
                           y_m=float(ey[0] + off * math.cos(eh[0])), heading_rad=float(eh[0]),
                           speed_mps=speed + rng.normal(0.0, 0.3), accel_mps2=0.0)
        out.append((predictions, ego))
        g += speed * 0.05
        speed = max(0.0, speed + rng.normal(0.0, 0.6))
    return out


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_dense_synthetic_obstacles_about_the_route(regimes, spy, scenario):
    runs = [r for p in PROFILES for r in regimes[scenario, p]]
    route = RoutePlanner(*runs[0].args).route
    rng = np.random.default_rng(7)
    streams = [synthetic_frames(route, rng, 60) for _ in runs]
    alone = [RoutePlanner(*r.args) for r in runs]
    batched = [RoutePlanner(*r.args) for r in runs]
    decisions = set()
    for k in range(60):
        preds, egos = [s[k][0] for s in streams], [s[k][1] for s in streams]
        plans = plan_batch(batched, preds, egos)
        for a, b, pr, e, plan in zip(alone, batched, preds, egos, plans, strict=True):
            assert plan_bits(plan) == plan_bits(a.plan(pr, e)), k
            assert state_bits(b) == state_bits(a), k
            decisions.add(plan.decision)
    assert {"cruise", "follow", "yield", "emergency_brake"} <= decisions
    assert len(spy["groups"]) == 2 * 60  # a group per profile, every frame
    assert any(held for _, _, held in spy["crossings"])
