"""The lockstep world (`evoeye.sim.lockstep_world`) leaves every world exactly where its own
`World.step` leaves it.

Each case steps B real runs twice, built as `run_episode` builds them (`build_world`, `_seeds`):
one copy per run with `World.step`, driven by its own ADS (so the commands are what an ADS
sends, braking into and after contacts), the other all together with `step_worlds`, given the
same commands. At every frame the scenes (`scenes` against `World.scene`) and every piece of
world state — each vehicle's pose, speed, crashed flag and the NPCs' drivers, scripts and
reaction buffers, the world's accelerations, blocked times, contacts, crossings — must agree to
the bit. The runs are picked so that contacts happen: ego with NPC, NPC with the crashed pair,
the `follower` striking the ego from behind; the test checks they did.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque

import numpy as np
import pytest

from evoeye.ads import ADS, ads_profile
from evoeye.batch import plan_uniform
from evoeye.boxes import box_corners, box_gaps
from evoeye.sim import lockstep_world
from evoeye.sim.lockstep_world import scenes, step_worlds
from evoeye.sim.runner import RATE_HZ, _seeds, build_world
from evoeye.sim.world import NPC_REACTION_S, World

DT = 1.0 / RATE_HZ

# (scenario, world variant, ADS profile, plan size, plan seed, the plan's runs to step): each
# batch holds runs that collide within its frames, the earliest first (a contact found in one
# world must not hide one found in a later world at the same step). First contacts: highway 43
# at frame 116 (the follower's at 158); intersection 12 at 100, 0 at 106, 5 at 148 (an NPC
# into the crashed pair at 153); crossing 31 at 63, 7 at 98.
HIGHWAY = [("highway-cut-in", "default", "default", 48, 3, (43, 0, 1)),
           ("highway-cut-in", "default", "cautious", 4, 5, (0, 1)),
           ("highway-cut-in", "follower", "default", 48, 3, (43, 2)),
           ("highway-cut-in", "follower", "cautious", 4, 5, (0,))]
INTERSECTION = [("unprotected-intersection", "default", "default", 16, 1, (12, 0, 5, 1)),
                ("unprotected-intersection", "default", "cautious", 4, 5, (0, 1))]
CROSSING = [("occluded-crossing", "default", "default", 48, 3, (31, 7, 1)),
            ("occluded-crossing", "default", "firm-yield", 4, 5, (0, 1))]

# left out of a snapshot: what a step never changes (the road, paths, driver models, scripts)
# and the vehicles, which are compared one by one
_STATIC = {"road", "path", "lane", "lane_index", "driver", "brake", "lane_change", "history",
           "log", "_curve_speed", "road_map", "ego_path", "vehicles", "ego", "npcs",
           "_on_curves", "_scripted"}


def _canon(value):
    """A value as plain data, floats and arrays by their bits and type, for `==`."""
    if isinstance(value, np.ndarray):
        return ("array", value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, float | np.floating):
        return (type(value).__name__, float(value).hex() if math.isfinite(value) else
                repr(float(value)))
    if isinstance(value, bool | int | str | type(None) | np.integer | np.bool_):
        return (type(value).__name__, value)
    if isinstance(value, list | tuple | deque):
        return (type(value).__name__, [_canon(v) for v in value])
    if isinstance(value, dict):
        return {k: _canon(v) for k, v in value.items()}
    fields = ([f.name for f in dataclasses.fields(value)] if dataclasses.is_dataclass(value)
              else list(vars(value)))
    return (type(value).__name__, {k: _canon(getattr(value, k)) for k in fields
                                   if k not in _STATIC})


def snapshot(world: World) -> dict:
    """Every piece of a world's state that a step may change (and the constants beside it)."""
    return {"world": _canon(world), "vehicles": [_canon(v) for v in world.vehicles]}


def _specs(cases):
    return [spec for scenario, world, ads, n, seed, picks in cases
            for spec in [plan_uniform(scenario, n, seed=seed, world=world, ads=ads)[k]
                         for k in picks]]


def _lockstep(cases, frames: int, monkeypatch) -> tuple[list[World], list[dict[int, list]], int]:
    """Step the runs of `cases` per run and in lockstep for `frames` frames, comparing at every
    frame. Returns the per-run worlds at the end; per lockstep step the contacts it found (world
    index → its touching pairs); and in how many frames some NPC answered a crossing car
    (blocked for longer than its reaction time)."""
    specs = _specs(cases)
    mine, theirs, drivers = [], [], []
    contacts: list[dict[int, list]] = []
    answered = 0
    crash = World._crash

    def record(world, i, j, x, y):
        if any(world is w for w in mine):
            contacts[-1][next(b for b, w in enumerate(mine) if w is world)] = list(zip(
                i.tolist(), j.tolist(), strict=True))
        crash(world, i, j, x, y)

    monkeypatch.setattr(World, "_crash", record)
    for spec in specs:
        world_rng, ads_rng = _seeds(spec.seed)
        world, cruise = build_world(spec, world_rng)
        theirs.append(world)
        drivers.append(ADS(world.road_map, ads_rng,
                           ads_profile(spec.ads).with_cruise_speed(cruise)))
        mine.append(build_world(spec)[0])
    for k in range(frames):
        want = [w.scene() for w in theirs]
        got = scenes(mine)
        for a, b in zip(got, want, strict=True):
            assert _canon(a) == _canon(b), f"scene at frame {k}"
        for a, b in zip(mine, theirs, strict=True):
            assert snapshot(a) == snapshot(b), f"world at frame {k}"
        controls = [ads.step(scene).control for ads, scene in zip(drivers, want, strict=True)]
        accels = [c.accel_cmd_mps2 for c in controls]
        steers = [c.steering_rad for c in controls]
        for w, a, s in zip(theirs, accels, steers, strict=True):
            w.step(a, s, DT)
        contacts.append({})
        step_worlds(mine, accels, steers, DT)
        answered += any(np.count_nonzero(w._blocked_s > NPC_REACTION_S) for w in theirs)
    for a, b in zip(mine, theirs, strict=True):
        assert snapshot(a) == snapshot(b), "world at the end"
    return theirs, contacts, answered


def _crashed(worlds: list[World]) -> list[list[int]]:
    return [w.crashed.nonzero()[0].tolist() for w in worlds]


def test_highway_and_its_follower_variant_step_together_bit_for_bit(monkeypatch) -> None:
    """Default and `follower` worlds (7 and 8 actors) in one batch: stepped as two groups."""
    worlds, contacts, _ = _lockstep(HIGHWAY, 170, monkeypatch)
    crashed = _crashed(worlds)
    assert [0, 2] in crashed  # the ego hit a cut-in …
    assert [0, 2, 7] in crashed  # … and the follower then struck the ego from behind
    assert any(n._lc_start_s is not None for w in worlds for n in w.npcs)  # lane changes
    assert any(n._reacting for w in worlds for n in w.npcs)  # the follower's buffer was used
    pairs = [p for step in contacts for found in step.values() for p in found]
    assert (2, 7) in pairs  # an NPC with an NPC
    assert any(len(found) >= 2 for step in contacts for found in step.values())


def test_intersection_steps_together_bit_for_bit(monkeypatch) -> None:
    worlds, contacts, answered = _lockstep(INTERSECTION, 160, monkeypatch)
    crashed = _crashed(worlds)
    assert [0, 2, 3] in crashed  # an NPC ran into a crashed pair
    assert sum(bool(c) for c in crashed) >= 3
    assert sum(len(step) >= 2 for step in contacts) > 10  # several worlds touching in one step
    assert any(c.first is not None for w in worlds for c in w.conflicts)
    assert any(y.going for w in worlds for y in w.yields)
    assert answered > 10


def test_occluded_crossing_steps_together_bit_for_bit(monkeypatch) -> None:
    worlds, _, answered = _lockstep(CROSSING, 110, monkeypatch)
    assert sum(bool(c) for c in _crashed(worlds)) >= 2
    assert all(w.collision_actor != -1 for w in worlds[:2])
    assert any(y.going for w in worlds for y in w.yields)  # a kerb pedestrian went
    assert answered > 10


@pytest.mark.parametrize("min_batch", [1, lockstep_world.MIN_BATCH])
@pytest.mark.parametrize("case", [HIGHWAY[2], INTERSECTION[0], CROSSING[0]],
                         ids=lambda c: c[0])
def test_one_world_is_its_own_step(case, min_batch, monkeypatch) -> None:
    """B = 1: the lockstep of one world is its step, through the batch's phases (MIN_BATCH = 1)
    as through the world's own methods (the default)."""
    monkeypatch.setattr(lockstep_world, "MIN_BATCH", min_batch)
    scenario, world, ads, n, seed, picks = case
    _lockstep([(scenario, world, ads, n, seed, picks[:1])], 40, monkeypatch)


def test_a_pairs_exact_gap_is_the_same_in_any_batch_of_pairs() -> None:
    """`box_gaps` of many pairs in one call, as the lockstep's contacts call it, equals it pair
    by pair and in any slice: boxes of cars, parked cars and pedestrians, touching or close."""
    rng = np.random.default_rng(0)
    n = 300
    size = rng.choice([[5.0, 2.0], [4.6, 1.9], [0.6, 0.6]], size=(2, n))
    x, y, h = rng.uniform(0.0, 6.0, n), rng.uniform(0.0, 3.0, n), rng.uniform(-3.2, 3.2, n)
    a = box_corners(x, y, h, size[0, :, 0], size[0, :, 1])
    b = box_corners(x + rng.uniform(-5.0, 5.0, n), y + rng.uniform(-3.0, 3.0, n),
                    rng.uniform(-3.2, 3.2, n), size[1, :, 0], size[1, :, 1])
    gaps = box_gaps(a, b)
    assert 0 < np.count_nonzero(gaps == 0.0) < n
    one_by_one = np.concatenate([box_gaps(a[k:k + 1], b[k:k + 1]) for k in range(n)])
    assert gaps.tobytes() == one_by_one.tobytes()
    for lo, hi in ((0, 7), (3, 64), (100, 101), (37, 300)):
        assert gaps[lo:hi].tobytes() == box_gaps(a[lo:hi], b[lo:hi]).tobytes()
    # corners of gathered rows are the gathered corners of all rows (the contacts gather first)
    rows = rng.integers(0, n, 50)
    assert box_corners(x[rows], y[rows], h[rows], size[0, rows, 0], size[0, rows, 1]).tobytes() \
        == a[rows].tobytes()


def test_step_worlds_needs_a_command_per_world() -> None:
    spec = plan_uniform("highway-cut-in", 1, seed=0)[0]
    with pytest.raises(ValueError, match="2 worlds, 1 accels"):
        step_worlds([build_world(spec)[0], build_world(spec)[0]], [0.0], [0.0, 0.0], DT)
